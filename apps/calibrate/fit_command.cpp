// calibrate fit SESSION... -o calibration.json [--sensor N] [--model auto|bias|scale|full] ...
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <memory>
#include <optional>

#include "cli_progress.hpp"
#include "commands.hpp"
#include "conformity_cli.hpp"
#include "load_cli.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/thermal_fit.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/certificate.hpp"
#include "registry_hooks.hpp"
#include "tags_cli.hpp"
#include "tags_names.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

struct FitOptions {
  std::vector<std::string> inputs;
  std::string output;
  bool imutk = false;  // Inputs are imu_tk pairs: ACC GYRO [ACC GYRO ...].
  // --sensor, --model, --accel-model, --gyro-model, --gravity-mps2, --accel-fs-g, --gyro-fs-dps,
  // --temperature, --loss, --loss-scale, --accel-only, --min-static-s: the library's options
  // and defaults, bound directly (--accel-model none is fit_accel = false).
  CalibrationOptions calibration;
  std::string segments;                // Annotated segments instead of the detector.
  std::string html;                    // Calibration certificate (docs/reports.md).
  bool accept_rejected_model = false;  // --accept-rejected-model: certify them anyway.
  std::string tags;                    // --tags FILE: device IDs into calibration.json.
  apps::LoadCliOptions load;    // --format, --column, --rate-hz, ... (--accel-fs-g is fit's).
  SpecCliOptions spec;          // --spec, --fail-on-nonconformity (docs/conformity.md)
  RegistryCliOptions registry;  // --registry, --station, --operator (docs/registry.md)
  // --thermal: bias versus temperature from one static record per tag (docs/thermal.md).
  bool thermal = false;
  ThermalFitOptions thermal_options;
};

// calibrate fit --thermal SESSION -o thermal.json: FitThermalTag per tag, one JSON document.
int RunThermalFit(const FitOptions& f) {
  if (f.imutk || !f.segments.empty() || !f.html.empty() || !f.spec.spec.empty() ||
      !f.registry.url.empty() || f.inputs.size() != 1) {
    apps::PrintErrorText(
        "--thermal takes one session (a static record over a temperature range) and -o; it "
        "does not take --imutk, --segments, --html, --spec or --registry (docs/thermal.md)");
    return kExitUsage;
  }
  std::string why;
  if (!f.thermal_options.IsValid(&why)) {
    apps::PrintErrorText("--thermal: " + why);
    return kExitUsage;
  }
  if (Status s = apps::CheckOutputs({{"-o", f.output}}, {{"SESSION", f.inputs.front()}}, {});
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  LoadOptions load;
  if (Status st = apps::MakeLoadOptions(f.load, &load); !st.ok()) {
    return apps::PrintErrorExit(st.error());
  }
  Result<Session> session = LoadSession(f.inputs.front(), load);
  if (!session.ok()) return apps::PrintErrorExit(session.error());
  std::vector<ThermalTagFit> fits;
  for (const Tag& tag : session.value().tags) {
    if (f.calibration.sensor != 0 && tag.sensor != f.calibration.sensor) continue;
    Result<ThermalTagFit> fit = FitThermalTag(tag, f.inputs.front(), f.thermal_options);
    if (!fit.ok()) return apps::PrintErrorExit(fit.error());
    // Both sensors read the same temp_c column: one warning per excluded line.
    for (int64_t line : fit.value().accel.excluded_lines) {
      apps::PrintWarning(
          fmt::format("{}:{}: temp_c is a read error (more than {} degC from its "
                      "neighbours' median): sample excluded",
                      f.inputs.front(), line, f.thermal_options.glitch_c));
    }
    fits.push_back(std::move(fit).value());
  }
  if (fits.empty()) {
    apps::PrintErrorText(
        f.calibration.sensor != 0
            ? fmt::format("{}: no tag {} in the session", f.inputs.front(), f.calibration.sensor)
            : fmt::format("{}: the session has no tags", f.inputs.front()));
    return kExitUsage;
  }
  if (Status w = apps::WriteOutputs({{f.output, ThermalFitJson(fits, f.thermal_options)}});
      !w.ok()) {
    return apps::PrintErrorExit(w.error());
  }
  for (const ThermalTagFit& t : fits) {
    apps::Note(fmt::format(
        "sensor {}: valid {:.2f} .. {:.2f} degC, orders accel {} {} {}, gyro "
        "{} {} {}\n",
        t.sensor, t.gyro.t_min_c, t.gyro.t_max_c, t.accel.axes[0].order, t.accel.axes[1].order,
        t.accel.axes[2].order, t.gyro.axes[0].order, t.gyro.axes[1].order, t.gyro.axes[2].order));
  }
  apps::Note(fmt::format("wrote {}\n", apps::IsStdio(f.output) ? "stdout" : f.output));
  return kExitOk;
}

int RunFit(const FitOptions& f) {
  if (f.thermal) return RunThermalFit(f);
  CalibrationOptions o = f.calibration;
  const bool accel_none = !o.fit_accel;
  if (accel_none && !o.fit_gyro) {
    apps::PrintErrorText("--accel-model none and --accel-only leave nothing to calibrate");
    return kExitUsage;
  }
  if (accel_none && (o.gyro_model != ModelKind::kBias || o.gyro_auto)) {
    apps::PrintErrorText(
        "--accel-model none evaluates the gyroscope's bias at rest from one static record: give "
        "--gyro-model bias (a scale or misalignment needs poses, rotations and the "
        "accelerometer)");
    return kExitUsage;
  }
  if (accel_none && !f.segments.empty()) {
    apps::PrintErrorText(
        "--segments does not apply to --accel-model none (the whole record is "
        "the static pose)");
    return kExitUsage;
  }
  if (!f.segments.empty()) {
    Result<std::vector<AnnotatedSegment>> given = ReadSegmentsFile(f.segments);
    if (!given.ok()) {
      return apps::PrintErrorExit(given.error());
    }
    o.annotated_segments = std::move(given).value();
    o.segments_path = f.segments;
  }
  std::string why;
  if (!o.IsValid(&why)) {
    apps::PrintErrorText(why);
    return kExitUsage;
  }
  if (f.imutk && f.inputs.size() % 2 != 0) {
    apps::PrintErrorText("--imutk takes pairs of files: ACC GYRO [ACC GYRO ...]");
    return kExitUsage;
  }
  if (Status s = apps::CheckStdinInputs(f.inputs, f.imutk); !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  if (Status s = apps::RefuseStdout(f.html, "--html", "the certificate goes to a file"); !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  std::vector<apps::NamedPath> inputs = {
      {"--columns-file", f.load.columns_file}, {"--segments", f.segments}, {"--spec", f.spec.spec}};
  for (const std::string& in : f.inputs) inputs.push_back({"SESSION", in});
  inputs.push_back({"--tags", f.tags});
  if (Status s = apps::CheckOutputs({{"-o", f.output}, {"--html", f.html}}, inputs,
                                    RegistryFiles(f.registry.url));
      !s.ok()) {
    return apps::PrintErrorExit(s.error());
  }
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(f.tags);
  if (!tags.ok()) {
    return apps::PrintErrorExit(tags.error());
  }
  const LoadedSpec spec = LoadSpecOption(f.spec);
  if (spec.exit_code != 0) return spec.exit_code;
  OpenedRegistry registry = OpenRegistryOption(f.registry);
  if (registry.exit_code != 0) return registry.exit_code;
  std::vector<Session> sessions;
  const size_t step = f.imutk ? 2 : 1;
  TerminalProgress progress(stderr, apps::CliProgressOptions());  // Loads (bytes), then the fit.
  for (size_t i = 0; i < f.inputs.size(); i += step) {
    LoadOptions load;
    if (Status st = apps::MakeLoadOptions(f.load, &load); !st.ok()) {
      return apps::PrintErrorExit(st.error());
    }
    if (!f.imutk) {
      BeginLoadPhase(&progress, f.inputs[i]);
      load.on_bytes_parsed = [&progress](int64_t n) { progress.Advance(n); };
    }
    Result<Session> s =
        f.imutk ? LoadImuTk(f.inputs[i], f.inputs[i + 1]) : LoadSession(f.inputs[i], load);
    progress.Finish();
    if (!s.ok()) {
      return apps::PrintErrorExit(s.error());
    }
    sessions.push_back(std::move(s).value());
  }
  std::vector<const Session*> ptrs;
  for (const Session& s : sessions) ptrs.push_back(&s);
  // Missing columns are bad input (exit 2), named with the file before any fitting.
  if (Status c = CheckCalibrationColumns(ptrs, o); !c.ok()) {
    return apps::PrintErrorExit(c.error());
  }
  progress.BeginPhase("fit (Ceres)", kUncountedWork);
  Result<Calibration> cal = CalibrateSessions(ptrs, o);
  progress.Finish();
  if (!cal.ok()) {
    return apps::PrintErrorExit(cal.error());
  }
  // calibration.json carries each tag's device ID, name and profile from the tags file (a
  // default body-part name only for the thesis tags' own records: none for other tools').
  const bool thesis_records = IsThesisTagFormat(apps::CalibrationRecordsFormat(cal.value()));
  for (TagCalibration& t : cal.value().tags) {
    const TagEntry* entry = tags.value() ? tags.value()->Find(t.sensor) : nullptr;
    if (entry != nullptr) {
      t.device_id = entry->device_id;
      if (thesis_records || !entry->thesis_default) t.name = entry->name;
      t.profile = entry->profile;
    }
  }
  if (int rc = ApplySpec(spec.spec, &cal.value()); rc != kExitOk) return rc;
  std::string html;
  if (!f.html.empty()) {
    // Constants marked model_rejected are not certified without --accept-rejected-model (an
    // input decision, exit 2; nothing is written).
    const std::vector<std::string> rejected = ModelRejectedConstants(cal.value());
    if (!rejected.empty() && !f.accept_rejected_model) {
      std::string list;
      for (const std::string& r : rejected) list += (list.empty() ? " " : "; ") + r;
      apps::PrintErrorText(fmt::format(
          "the certificate refuses constants marked model_rejected (nothing written):{}. Refit "
          "as the reason says, drop --html to write calibration.json alone (`characterize "
          "report calibration.json --html PAGE.html` then shows it as a page that is not a "
          "certificate), or give --accept-rejected-model to certify them with that notice",
          list));
      return kExitUsage;
    }
    CertificateOptions certificate;
    certificate.accept_rejected_model = f.accept_rejected_model;
    Result<std::string> rendered = RenderCalibrationCertificate(cal.value(), certificate);
    if (!rendered.ok()) {
      // The certificate of the fit just made: a failure is the run's, not the input's.
      return apps::PrintErrorExit(rendered.error().WithKind(ErrorKind::kFailed));
    }
    html = std::move(rendered).value();
  }
  // calibration.json and its certificate are replaced together or not at all.
  if (Status w =
          apps::WriteOutputs({{f.output, FormatCalibrationJson(cal.value())}, {f.html, html}});
      !w.ok()) {
    return apps::PrintErrorExit(w.error());
  }
  // The summary is a note (not under --quiet); the warnings always print.
  for (const TagCalibration& t : cal.value().tags) {
    std::map<SegmentKind, int> counts;
    for (const Segment& s : t.segments) ++counts[s.kind];
    apps::Note(fmt::format(
        "sensor {}: {} static, {} table, {} rotation segments{} (factor {})\n", t.sensor,
        counts[SegmentKind::kStatic], counts[SegmentKind::kTable], counts[SegmentKind::kRotation],
        counts[SegmentKind::kSteady] > 0
            ? fmt::format(", {} steady rotations excluded", counts[SegmentKind::kSteady])
            : "",
        t.threshold_factor));
    if (t.accel) {
      apps::Note(fmt::format("  accel residual rms {:.3g} {} ({:.3g} m/s^2)\n",
                             t.accel->residual_rms, t.accel->residual_unit,
                             t.accel->residual_rms * kStandardGravityMps2));
    }
    if (t.gyro) {
      apps::Note(fmt::format("  gyro residual rms {:.3g} {}\n", t.gyro->residual_rms,
                             t.gyro->residual_unit));
      if (!o.fit_accel) {
        // The bias at rest: value, u (k = 1) and the 95 % coverage factor, per axis.
        const SensorCalibration& g = *t.gyro;
        for (int a = 0; a < 3; ++a) {
          apps::Note(fmt::format(
              "  gyro bias at rest {}: {:.6g} {} u {:.3g} {} ({:.4g} u {:.2g} deg/s; k95 {:.3g}, "
              "dof {})\n",
              "xyz"[a], g.model.bias[a], g.model.input_unit, g.bias_u[a], g.model.input_unit,
              g.model.bias[a] * g.model.scale[a], g.bias_u[a] * g.model.scale[a],
              g.coverage_factor_95, g.dof));
        }
      }
    }
    for (const std::string& w : t.warnings) {
      if (apps::Quiet()) {
        apps::PrintWarning(fmt::format("sensor {}: {}", t.sensor, w));
      } else {
        apps::PrintWarning(w, "  ");
      }
    }
  }
  apps::Note(fmt::format("wrote {}\n", apps::IsStdio(f.output) ? "stdout" : f.output));
  if (!f.html.empty()) apps::Note(fmt::format("wrote {}\n", f.html));
  int rc = ConformityExitCode(f.spec, cal.value());
  if (registry.registry) {
    const Result<std::vector<int64_t>> ids = registry.registry->RecordCalibration(
        cal.value(), CalibrationCertificateId(cal.value()), f.registry.Context());
    rc = std::max(rc, RegistryResult(ids.status(), fmt::format("{} tag calibration(s)",
                                                               cal.value().tags.size())));
  }
  return rc;
}

}  // namespace

void AddFitCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<FitOptions>();
  CLI::App* sub = app.add_subcommand(
      "fit",
      "fit the calibration of every tag in the sessions (static poses, table runs, "
      "hand rotations) and write calibration.json");
  sub->add_option("sessions", o->inputs,
                  "SESSION... (session.csv; ACC GYRO pairs with --imutk); - reads stdin")
      ->required()
      ->check(apps::ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "calibration.json to write (- for stdout)")->required();
  sub->add_flag("--imutk", o->imutk, "inputs are imu_tk file pairs: ACC GYRO [ACC GYRO ...]");
  apps::AddLoadCliOptions(sub, &o->load, /*full_scale_flags=*/false);
  CalibrationOptions& c = o->calibration;
  sub->add_option("--sensor", c.sensor, "calibrate only this tag (0 = every tag)");
  // --model sets both sensors' model unless --accel-model or --gyro-model names its own
  // (callbacks run once the whole command line is parsed, so the counts are final). The
  // default is auto (issue #36): the smallest model of bias < scale < full the data accept.
  c.accel_auto = true;
  c.gyro_auto = true;
  c.compare_models = true;
  const auto model_kind = [](const std::string& name) { return *ParseModelKind(name); };
  sub->add_option_function<std::string>(
         "--model",
         [o, sub, model_kind](const std::string& v) {
           const bool automatic = v == "auto";
           if (sub->count("--accel-model") == 0) {
             o->calibration.accel_auto = automatic;
             if (!automatic) o->calibration.accel_model = model_kind(v);
           }
           if (sub->count("--gyro-model") == 0) {
             o->calibration.gyro_auto = automatic;
             if (!automatic) o->calibration.gyro_model = model_kind(v);
           }
         },
         "auto (default: the smallest model the data accept) | bias | scale | full, for both "
         "sensors")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full"}));
  sub->add_option_function<std::string>(
         "--accel-model",
         [o, model_kind](const std::string& v) {
           o->calibration.accel_auto = v == "auto";
           if (v == "none") {
             o->calibration.fit_accel = false;  // The accel model stays --model's (unused).
           } else if (v != "auto") {
             o->calibration.accel_model = model_kind(v);
           }
         },
         "override --model for the accelerometer: auto | bias | scale | full, or none (with "
         "--gyro-model bias: the gyroscope's bias at rest from one static record)")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full", "none"}));
  sub->add_option_function<std::string>(
         "--gyro-model",
         [o, model_kind](const std::string& v) {
           o->calibration.gyro_auto = v == "auto";
           if (v != "auto") o->calibration.gyro_model = model_kind(v);
         },
         "override --model for the gyroscope: auto | bias | scale | full")
      ->check(CLI::IsMember({"auto", "bias", "scale", "full"}));
  sub->add_option("--gravity-mps2", c.gravity_mps2,
                  "local gravity [m/s^2] (default: standard gravity 9.80665, CGPM 1901)")
      ->check(CLI::PositiveNumber);
  sub->add_option_function<double>(
      "--gravity-u-mps2", [o](double v) { o->calibration.gravity_u_mps2 = v; },
      "standard uncertainty of --gravity-mps2 [m/s^2], stated in calibration.json and in the "
      "certificate's accelerometer budget");
  sub->add_option("--accel-fs-g", c.accel_fs_g, "accelerometer full scale of raw counts [g]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--gyro-fs-dps", c.gyro_fs_dps, "gyroscope full scale of raw counts [deg/s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option_function<std::string>(
         "--temperature",
         [o](const std::string& v) {
           o->calibration.temperature = v == "on"    ? TemperatureMode::kOn
                                        : v == "off" ? TemperatureMode::kOff
                                                     : TemperatureMode::kAuto;
         },
         "linear temperature term of the biases: auto (when temp_c varies), on, off")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  sub->add_option_function<std::string>(
         "--loss", [o](const std::string& v) { o->calibration.loss = *ParseLossKind(v); },
         "robust loss: none | huber | cauchy")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}));
  sub->add_option("--loss-scale", c.loss_scale, "robust loss scale, in standard deviations")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag_callback(
      "--accel-only", [o] { o->calibration.fit_gyro = false; }, "calibrate the accelerometer only");
  sub->add_option("--min-static-s", c.segmentation.min_static_s,
                  "shortest still period kept as a pose [s] (default 1; below 1 s the detector's "
                  "window shrinks with it, so poses of about twice this are found)");
  sub->add_option("--segments", o->segments,
                  "CSV of annotated segments used instead of the static detector: "
                  "kind,start_s,end_s[,table_rate_dps][,input] (docs/calibration-model.md)")
      ->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "also write the calibration certificate (HTML) here");
  sub->add_flag("--thermal", o->thermal,
                "bias versus temperature (polynomial, order by F-tests) from one static record "
                "over a temperature range; writes metro.thermal-fit/1 JSON (docs/thermal.md)");
  sub->add_option("--thermal-order", o->thermal_options.order,
                  "--thermal: fixed polynomial order 1..4 (0: chosen by the data)")
      ->check(CLI::Range(0, 4))
      ->capture_default_str();
  sub->add_option("--thermal-bin-c", o->thermal_options.bin_width_c,
                  "--thermal: temperature bin width; every bin weighs the same")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "certify constants marked model_rejected (a model the data reject or an exact "
                "fit), with that notice on the certificate");
  AddTagsOption(sub, &o->tags);
  AddSpecOptions(sub, &o->spec);
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code, sub] {
    o->calibration.gravity_given = sub->count("--gravity-mps2") > 0;
    *exit_code = RunFit(*o);
  });
}

}  // namespace metro::calibrate_app
