#include "noise_export_options.hpp"

#include "metro/core/file.hpp"
#include "metro/report/noise_export_input.hpp"
#include "metro/report/session_report.hpp"

namespace metro::apps {

std::vector<std::string> NoiseExportFormatNames() {
  std::vector<std::string> names;
  for (NoiseExportFormat f : kAllNoiseExportFormats) names.emplace_back(NoiseExportFormatName(f));
  return names;
}

std::string DefaultSpecLibrary() { return METRO_SPEC_LIBRARY; }

void AddAxisReductionOption(CLI::App* app, AxisReduction* reduction, const std::string& help) {
  app->add_option_function<std::string>(
         "--axis-reduction",
         [reduction](const std::string& value) {
           Result<AxisReduction> r = ParseAxisReduction(value);
           if (!r.ok()) throw CLI::ValidationError("--axis-reduction", r.error().message);
           *reduction = r.value();
         },
         help)
      ->check(CLI::IsMember(
          {AxisReductionName(AxisReduction::kMax), AxisReductionName(AxisReduction::kRms)}))
      ->default_str(AxisReductionName(*reduction));
}

void AddNoiseExportCliOptions(CLI::App* app, NoiseExportCliOptions* o) {
  app->add_option_function<int64_t>(
      "--sensor", [o](int64_t n) { o->sensor = n; },
      "the tag whose terms to take (default: the one tag with an Allan section)");
  AddAxisReductionOption(app, &o->library.reduction,
                         "one value over the three axes for the scalar formats: max (the "
                         "largest axis and its u) or rms");
  app->add_option("--rostopic", o->library.rostopic, "kalibr, openvins: the IMU topic named")
      ->capture_default_str();
  app->add_option("--px4-predict-rate-hz", o->library.px4_predict_rate_hz,
                  "px4-ekf2: the EKF2 prediction rate its parameters are per step of")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

Result<NoiseExportInput> LoadNoiseExportInput(const NoiseExportCliOptions& o) {
  std::string why;
  if (!o.library.IsValid(&why)) return MakeError(why);
  Result<std::string> text = ReadFile(o.report);
  if (!text.ok()) return text.error();
  Result<SessionReport> report = SessionReportFromJson(text.value(), o.report);
  if (!report.ok()) return report.error();
  return NoiseExportInputFromReport(report.value(), o.report, o.sensor);
}

}  // namespace metro::apps
