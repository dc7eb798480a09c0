// calibrate fit SESSION... -o calibration.json [--sensor N] [--model auto|bias|scale|full] ...
#include "fit_command.hpp"

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
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

// --thermal takes one static record over a temperature range and -o, and its own options.
Status CheckThermalFitOptions(const FitOptions& f) {
  if (f.imutk || !f.segments.empty() || !f.html.empty() || !f.spec.spec.empty() ||
      !f.registry.url.empty() || f.inputs.size() != 1) {
    return MakeError(
        "--thermal takes one session (a static record over a temperature range) and -o; it "
        "does not take --imutk, --segments, --html, --spec or --registry (docs/thermal.md)");
  }
  std::string why;
  if (!f.thermal_options.IsValid(&why)) return MakeError("--thermal: " + why);
  return apps::CheckOutputs({{"-o", f.output}}, {{"SESSION", f.inputs.front()}}, {});
}

// FitThermalTag of every tag of the session (or --sensor's), with a warning per excluded
// temperature read error (both sensors read the same temp_c column: one per line).
Result<std::vector<ThermalTagFit>> FitThermalTags(const FitOptions& f, const Session& session) {
  std::vector<ThermalTagFit> fits;
  for (const Tag& tag : session.tags) {
    if (f.calibration.sensor != 0 && tag.sensor != f.calibration.sensor) continue;
    Result<ThermalTagFit> fit = FitThermalTag(tag, f.inputs.front(), f.thermal_options);
    if (!fit.ok()) return fit.error();
    for (int64_t line : fit.value().accel.excluded_lines) {
      apps::PrintWarning(
          fmt::format("{}:{}: temp_c is a read error (more than {} degC from its "
                      "neighbours' median): sample excluded",
                      f.inputs.front(), line, f.thermal_options.glitch_c));
    }
    fits.push_back(std::move(fit).value());
  }
  if (fits.empty()) {
    return MakeError(
        f.calibration.sensor != 0
            ? fmt::format("{}: no tag {} in the session", f.inputs.front(), f.calibration.sensor)
            : fmt::format("{}: the session has no tags", f.inputs.front()));
  }
  return fits;
}

// calibrate fit --thermal SESSION -o thermal.json: FitThermalTag per tag, one JSON document.
int RunThermalFit(const FitOptions& f) {
  if (Status s = CheckThermalFitOptions(f); !s.ok()) return apps::PrintErrorExit(s.error());
  LoadOptions load;
  if (Status st = apps::MakeLoadOptions(f.load, &load); !st.ok()) {
    return apps::PrintErrorExit(st.error());
  }
  Result<Session> session = LoadSession(f.inputs.front(), load);
  if (!session.ok()) return apps::PrintErrorExit(session.error());
  Result<std::vector<ThermalTagFit>> fits = FitThermalTags(f, session.value());
  if (!fits.ok()) return apps::PrintErrorExit(fits.error());
  if (Status w = apps::WriteOutputs({{f.output, ThermalFitJson(fits.value(), f.thermal_options)}});
      !w.ok()) {
    return apps::PrintErrorExit(w.error());
  }
  for (const ThermalTagFit& t : fits.value()) {
    apps::Note(fmt::format(
        "sensor {}: valid {:.2f} .. {:.2f} degC, orders accel {} {} {}, gyro "
        "{} {} {}\n",
        t.sensor, t.gyro.t_min_c, t.gyro.t_max_c, t.accel.axes[0].order, t.accel.axes[1].order,
        t.accel.axes[2].order, t.gyro.axes[0].order, t.gyro.axes[1].order, t.gyro.axes[2].order));
  }
  apps::Note(fmt::format("wrote {}\n", apps::IsStdio(f.output) ? "stdout" : f.output));
  return kExitOk;
}

// The inputs and outputs, checked before anything is read: imu_tk pairs, stdin read once, no
// certificate to stdout, no output that names an input or the registry's files.
Status CheckFitFiles(const FitOptions& f) {
  if (f.imutk && f.inputs.size() % 2 != 0) {
    return MakeError("--imutk takes pairs of files: ACC GYRO [ACC GYRO ...]");
  }
  if (Status s = apps::CheckStdinInputs(f.inputs, f.imutk); !s.ok()) return s;
  if (Status s = apps::RefuseStdout(f.html, "--html", "the certificate goes to a file"); !s.ok()) {
    return s;
  }
  std::vector<apps::NamedPath> inputs = {
      {"--columns-file", f.load.columns_file}, {"--segments", f.segments}, {"--spec", f.spec.spec}};
  for (const std::string& in : f.inputs) inputs.push_back({"SESSION", in});
  inputs.push_back({"--tags", f.tags});
  return apps::CheckOutputs({{"-o", f.output}, {"--html", f.html}}, inputs,
                            RegistryFiles(f.registry.url));
}

// The sessions (imu_tk pairs: one session per pair), with a progress line per file.
Result<std::vector<Session>> LoadFitSessions(const FitOptions& f, TerminalProgress* progress) {
  std::vector<Session> sessions;
  const size_t step = f.imutk ? 2 : 1;
  for (size_t i = 0; i < f.inputs.size(); i += step) {
    LoadOptions load;
    if (Status st = apps::MakeLoadOptions(f.load, &load); !st.ok()) return st.error();
    if (!f.imutk) {
      BeginLoadPhase(progress, f.inputs[i]);
      load.on_bytes_parsed = [progress](int64_t n) { progress->Advance(n); };
    }
    Result<Session> s =
        f.imutk ? LoadImuTk(f.inputs[i], f.inputs[i + 1]) : LoadSession(f.inputs[i], load);
    progress->Finish();
    if (!s.ok()) return s.error();
    sessions.push_back(std::move(s).value());
  }
  return sessions;
}

// The certificate of --html. Constants marked model_rejected are not certified without
// --accept-rejected-model (an input decision, exit 2; nothing is written).
Result<std::string> FitCertificate(const Calibration& cal, const FitOptions& f) {
  const std::vector<std::string> rejected = ModelRejectedConstants(cal);
  if (!rejected.empty() && !f.accept_rejected_model) {
    std::string list;
    for (const std::string& r : rejected) list += (list.empty() ? " " : "; ") + r;
    return MakeError(fmt::format(
        "the certificate refuses constants marked model_rejected (nothing written):{}. Refit "
        "as the reason says, drop --html to write calibration.json alone (`characterize "
        "report calibration.json --html PAGE.html` then shows it as a page that is not a "
        "certificate), or give --accept-rejected-model to certify them with that notice",
        list));
  }
  CertificateOptions certificate;
  certificate.accept_rejected_model = f.accept_rejected_model;
  Result<std::string> rendered = RenderCalibrationCertificate(cal, certificate);
  // The certificate of the fit just made: a failure is the run's, not the input's.
  if (!rendered.ok()) return rendered.error().WithKind(ErrorKind::kFailed);
  return rendered;
}

// The gyroscope's bias at rest (--accel-model none): value, u (k = 1) and the 95 % coverage
// factor, per axis.
void NoteBiasAtRest(const SensorCalibration& g) {
  for (int a = 0; a < 3; ++a) {
    apps::Note(fmt::format(
        "  gyro bias at rest {}: {:.6g} {} u {:.3g} {} ({:.4g} u {:.2g} deg/s; k95 {:.3g}, "
        "dof {})\n",
        "xyz"[a], g.model.bias[a], g.model.input_unit, g.bias_u[a], g.model.input_unit,
        g.model.bias[a] * g.model.scale[a], g.bias_u[a] * g.model.scale[a], g.coverage_factor_95,
        g.dof));
  }
}

// Per tag: its segments, residuals and warnings. The summary is a note (not under --quiet);
// the warnings always print.
void PrintFitSummary(const Calibration& cal, const CalibrationOptions& o) {
  for (const TagCalibration& t : cal.tags) {
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
      if (!o.fit_accel) NoteBiasAtRest(*t.gyro);
    }
    for (const std::string& w : t.warnings) {
      if (apps::Quiet()) {
        apps::PrintWarning(fmt::format("sensor {}: {}", t.sensor, w));
      } else {
        apps::PrintWarning(w, "  ");
      }
    }
  }
}

// Loads the sessions, checks their columns (missing ones are bad input, exit 2, named with the
// file before any fitting) and fits.
Result<Calibration> Fit(const FitOptions& f, const CalibrationOptions& o) {
  TerminalProgress progress(stderr, apps::CliProgressOptions());  // Loads (bytes), then the fit.
  Result<std::vector<Session>> sessions = LoadFitSessions(f, &progress);
  if (!sessions.ok()) return sessions.error();
  std::vector<const Session*> ptrs;
  for (const Session& s : sessions.value()) ptrs.push_back(&s);
  if (Status c = CheckCalibrationColumns(ptrs, o); !c.ok()) return c.error();
  progress.BeginPhase("fit (Ceres)", kUncountedWork);
  Result<Calibration> cal = CalibrateSessions(ptrs, o);
  progress.Finish();
  return cal;
}

}  // namespace

int RunFit(const FitOptions& f) {
  if (f.thermal) return RunThermalFit(f);
  Result<CalibrationOptions> o = ResolveFitOptions(f.calibration, f.segments);
  if (!o.ok()) return apps::PrintErrorExit(o.error());
  if (Status s = CheckFitFiles(f); !s.ok()) return apps::PrintErrorExit(s.error());
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(f.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  const LoadedSpec spec = LoadSpecOption(f.spec);
  if (spec.exit_code != 0) return spec.exit_code;
  OpenedRegistry registry = OpenRegistryOption(f.registry);
  if (registry.exit_code != 0) return registry.exit_code;
  Result<Calibration> cal = Fit(f, o.value());
  if (!cal.ok()) return apps::PrintErrorExit(cal.error());
  if (tags.value()) NameFittedTags(*tags.value(), &cal.value());
  if (int rc = ApplySpec(spec.spec, &cal.value()); rc != kExitOk) return rc;
  Result<std::string> html = f.html.empty() ? std::string() : FitCertificate(cal.value(), f);
  if (!html.ok()) return apps::PrintErrorExit(html.error());
  // calibration.json and its certificate are replaced together or not at all.
  if (Status w = apps::WriteOutputs(
          {{f.output, FormatCalibrationJson(cal.value())}, {f.html, html.value()}});
      !w.ok()) {
    return apps::PrintErrorExit(w.error());
  }
  PrintFitSummary(cal.value(), o.value());
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

}  // namespace metro::calibrate_app
