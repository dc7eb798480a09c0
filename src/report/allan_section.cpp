#include "metro/report/allan_section.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "metro/io/columns.hpp"
#include "metro/noise/allan_report.hpp"

namespace metro {

Status AddAllanToReport(const Session& session, const SessionTypeA& type_a,
                        const SessionAllanOptions& options, nlohmann::ordered_json* report,
                        std::string* csv) {
  using json = nlohmann::ordered_json;
  std::string why;
  if (!options.allan.IsValid(&why)) return MakeError("invalid --allan options: " + why);
  size_t analysed = 0;
  auto& sensors = (*report)["sensors"];
  for (size_t k = 0; k < type_a.tags.size(); ++k) {
    const TagTypeA& t = type_a.tags[k];
    const Tag* tag = session.FindTag(t.sensor);
    METRO_CHECK(tag != nullptr);
    json& jtag = sensors[k];
    for (const QuantityTypeA& q : t.quantities) {
      const bool wanted = options.quantities.empty()
                              ? IsRateQuantity(q.name)
                              : std::find(options.quantities.begin(), options.quantities.end(),
                                          q.name) != options.quantities.end();
      if (!wanted) continue;
      ++analysed;
      json& jq = jtag["quantities"][q.name];
      const Quantity* values = tag->Find(q.name);
      const auto b = static_cast<ptrdiff_t>(t.window.begin);
      const auto e = static_cast<ptrdiff_t>(t.window.end);
      const std::vector<uint32_t> line(tag->line.begin() + b, tag->line.begin() + e);
      const std::vector<double> rate(values->values.begin() + b, values->values.begin() + e);
      // tau0 from exact integer differences when the file's time was integer (t_ns).
      auto period = tag->t_ns.size() == tag->t_s.size()
                        ? EstimateSamplePeriodNs(
                              std::vector<int64_t>(tag->t_ns.begin() + b, tag->t_ns.begin() + e),
                              line, options.period)
                        : EstimateSamplePeriod(
                              std::vector<double>(tag->t_s.begin() + b, tag->t_s.begin() + e), line,
                              options.period);
      if (!period.ok()) {
        Error err = period.error();
        err.file = session.path;
        jq["allan"] = {{"error", err.ToString()}};
        continue;
      }
      auto curve = ComputeAllan(rate, period.value().tau0_s, options.allan);
      if (!curve.ok()) {
        jq["allan"] = {{"error", curve.error().message}};
        continue;
      }
      auto fit = FitNoiseTerms(curve.value(), options.fit);
      const NoiseFit noise_fit = fit.ok() ? fit.value() : NoiseFit{};
      json allan = AllanToJson(curve.value(), noise_fit, q.unit);
      const SamplePeriod& p = period.value();
      allan["sample_period"] = {{"tau0_s", p.tau0_s},
                                {"rate_hz", p.rate_hz},
                                {"mean_dt_s", p.mean_dt_s},
                                {"jitter_rms_s", p.jitter_rms_s},
                                {"max_abs_jitter_s", p.max_abs_jitter_s},
                                {"missing_samples", p.missing_samples},
                                {"warnings", p.warnings}};
      if (!fit.ok()) allan["fit_error"] = fit.error().message;
      jq["allan"] = allan;
      jq["allan_type_a_link"] =
          AllanTypeALinkToJson(curve.value(), noise_fit, t.window.t_last_s - t.window.t_first_s);
      if (csv != nullptr) {
        *csv += fmt::format("# sensor {} {}\n", t.sensor, q.name);
        *csv += AllanCurveCsv(curve.value(), q.unit);
      }
    }
  }
  if (analysed == 0) {
    return MakeError(session.path, 0,
                     "--allan: no rate quantity (gyroscope or accelerometer column) in the "
                     "window; name one with --quantity");
  }
  return Status::Ok();
}

}  // namespace metro
