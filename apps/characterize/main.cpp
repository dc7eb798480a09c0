// characterize: GUM Type A/Type B evaluation, Monte Carlo and noise analysis of IMU tag
// sessions. The command line: every subcommand's flags bound to its options struct
// (*_command.hpp) and its Run function as the callback. This is the program's one translation
// unit that includes CLI11 (issue #39: CLI11 is header-only and costs seconds of compile time
// per file); the work is done by the commands and the metro library.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <new>

#include "accuracy_command.hpp"
#include "analysis_options.hpp"
#include "analyze_command.hpp"
#include "batch_command.hpp"
#include "budget_command.hpp"
#include "capture_command.hpp"
#include "cli_flags.hpp"
#include "convert_command.hpp"
#include "metro/noise/allan.hpp"
#include "metro/uncertainty/session_resolver.hpp"
#include "noise_compare_command.hpp"
#include "noise_export_command.hpp"
#include "noise_export_options.hpp"
#include "report_command.hpp"
#include "simulate_command.hpp"
#include "topics_command.hpp"

namespace metro::apps {
namespace {

// CheckModeOptions' view of a parsed command line.
OptionGiven GivenOn(const CLI::App& app) {
  return [&app](const std::string& name) {
    return app.get_option_no_throw(name) != nullptr && app.count(name) > 0;
  };
}

void AddAnalysisCliOptions(CLI::App* app, AnalysisCliOptions* o,
                           AnalysisCliKind kind = AnalysisCliKind::kTypeA) {
  const bool type_a = kind == AnalysisCliKind::kTypeA;
  AddLoadCliOptions(app, &o->load);
  app->add_option("--skip-samples", o->window.skip_samples,
                  "drop the first N observations of each tag")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--skip-seconds", o->window.skip_seconds,
                  "drop each tag's observations in its first S seconds")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--from-s", o->window.from_s, "keep observations with t_s >= this");
  app->add_option("--to-s", o->window.to_s, "keep observations with t_s <= this");
  // none|auto -> WindowOptions::settle_auto.
  app->add_option_function<std::string>(
         "--settle", [o](const std::string& value) { o->window.settle_auto = value == "auto"; },
         type_a ? "auto: drop each quantity's start-up transient (fitted exponential, "
                  "cut where the rest biases the mean by <= 0.1 u; docs/type-a.md)"
                : "auto: also drop each plateau's start-up transient (MSER-5; "
                  "docs/accuracy.md)")
      ->check(CLI::IsMember({"none", "auto"}))
      ->default_str(o->window.settle_auto ? "auto" : "none");
  app->add_option("--tags,--tag-registry", o->tag_registry,
                  R"(tags file, JSON {"1": "Forehead", "2": {"name": "Chest", "device_id": ...}} )"
                  R"(naming the tags (docs/formats.md "Tags file"; default: thesis Table 5.2))")
      ->check(CLI::ExistingFile);
  if (!type_a) {
    app->add_option("--sensor", o->sensors, "the tag to evaluate (default: the first)");
    return;
  }
  // quantity|tag -> WindowOptions::settle_tag_wide.
  app->add_option_function<std::string>(
         "--settle-scope",
         [o](const std::string& value) { o->window.settle_tag_wide = value == "tag"; },
         "with --settle auto: quantity (each from its own settle point) or tag (every "
         "quantity of a tag from the largest non-temperature cut)")
      ->check(CLI::IsMember({"quantity", "tag"}))
      ->default_str(o->window.settle_tag_wide ? "tag" : "quantity");
  app->add_option("--sensor", o->sensors, "only this tag (repeatable)");
  app->add_option("--quantity", o->quantities, "only this quantity, e.g. pitch_deg (repeatable)");
  app->add_flag("--allan", o->allan,
                "Allan deviation and IEEE 952 noise terms of the rate quantities (docs/noise.md)");
  // The library's parsers, so the flags accept exactly what the library does; a value they
  // refuse is a usage error naming the flag (exit 2).
  app->add_option_function<std::string>(
         "--taus",
         [o](const std::string& value) {
           Result<TauSpacing> taus = ParseTauSpacing(value);
           if (!taus.ok()) throw CLI::ValidationError("--taus", taus.error().message);
           o->allan_options.allan.taus = taus.value();
         },
         "Allan taus: octave, decade:N, all")
      ->default_str(TauSpacingName(o->allan_options.allan.taus));
  app->add_option_function<std::string>(
         "--estimator",
         [o](const std::string& value) {
           Result<AllanEstimator> estimator = ParseAllanEstimator(value);
           if (!estimator.ok())
             throw CLI::ValidationError("--estimator", estimator.error().message);
           o->allan_options.allan.estimator = estimator.value();
         },
         "Allan estimator: oadev, mdev, ohdev")
      ->default_str(AllanEstimatorName(o->allan_options.allan.estimator));
  app->add_option_function<std::string>(
         "--gaps",
         [o](const std::string& value) {
           Result<AllanGapPolicy> gaps = ParseAllanGapPolicy(value);
           if (!gaps.ok()) throw CLI::ValidationError("--gaps", gaps.error().message);
           o->allan_options.gaps = gaps.value();
         },
         "Allan through missing samples: skip (leave out the terms that read one, "
         "NIST SP 1065), split (the longest gap-free stretch only) or refuse "
         "(docs/noise.md)")
      ->check(CLI::IsMember({"skip", "split", "refuse"}))
      ->default_str(AllanGapPolicyName(o->allan_options.gaps));
}

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

void AddAccuracyOptions(CLI::App& app, AccuracyCliOptions* o) {
  app.add_flag("--accuracy", o->enabled,
               "accuracy against a rotation table: plateaus, error curve, hysteresis, budget "
               "(docs/accuracy.md)");
  app.add_option("--table-axis", o->table_axis, "the tag axis the table turns")
      ->type_name("TEXT:{yaw,pitch,roll}")
      ->capture_default_str();
  app.add_option("--reference", o->reference,
                 "separate reference log (t_s, table_angle_deg), aligned on t_s; - reads stdin")
      ->check(ExistingFileOrStdin());
  app.add_option("--reference-u", o->reference_u,
                 "the table's standard uncertainty in deg, or a budget file for it "
                 "(docs/budget-format.md)");
  app.add_option("--reference-offset-s", o->library.alignment.offset_s,
                 "reference clock minus tag clock in s (default: estimated)");
  app.add_option("--error-model", o->model,
                 "the fitted error curve (auto: the order the data support; docs/accuracy.md)")
      ->type_name("TEXT:{auto,linear,harmonic1,harmonic2}")
      ->capture_default_str();
  app.add_option("--min-dwell-s", o->library.plateaus.min_dwell_s,
                 "shortest table rest that is a plateau")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--settle-s", o->library.plateaus.settle_s,
                 "seconds dropped after the table stops")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--plateau-tolerance-deg", o->library.plateaus.tolerance_deg,
                 "largest reference change within a plateau")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--assumed-hysteresis-deg", o->library.assumed_hysteresis_deg,
                 "hysteresis the corrected U assumes when no angle was visited both ways")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--lag-tau-s", o->library.lag_tau_s,
                 "the tag's response time in s (default: estimated from the motion)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--no-lag-model", o->no_lag_model,
               "do not model the tag's lag: plateaus settle by --settle-s alone");
  app.add_flag("--keep-departures", o->keep_departures,
               "keep a plateau's start and end where the tag's error departs from its level "
               "(default: trimmed and said so)");
}

void AddAccuracyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AccuracyCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "accuracy",
      "accuracy of a tag against a rotation table: plateaus, error curve, hysteresis, budget "
      "(docs/accuracy.md; also: characterize SESSION --accuracy ...)");
  sub->add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  AddAnalysisCliOptions(sub, &o->analysis, AnalysisCliKind::kAccuracy);
  sub->add_option("-o,--output", o->output,
                  "write the JSON report here (atomically) and print a table to stdout; -o - "
                  "writes it to stdout and the table to stderr (default: the JSON to stdout)");
  sub->add_option("--html", o->html, "also write the HTML view here (docs/reports.md)");
  AddAccuracyOptions(*sub, &o->accuracy);
  sub->add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->callback([o, exit_code] { *exit_code = RunAccuracyCommand(*o); });
}

// SESSION and the Type A options, on the top-level app (`accuracy`: also the accuracy
// options, for the --accuracy spelling) or on the `analyze` subcommand.
void AddTypeAOptions(CLI::App& app, AnalyzeOptions* o, bool accuracy) {
  CLI::Option* session =
      app.add_option("session", o->session, "session.csv or receiver capture; - reads stdin")
          ->check(ExistingFileOrStdin());
  if (!accuracy) session->required();
  app.add_flag("--type-a", o->type_a,
               accuracy ? "GUM Type A evaluation of every quantity per tag (the default analysis)"
                        : "GUM Type A evaluation of every quantity per tag (implied: accepted "
                          "for the spelling without the subcommand)");
  AddAnalysisCliOptions(&app, &o->analysis);
  app.add_option("-o,--output", o->output,
                 "write the JSON report here (atomically) and print a table to stdout; -o - "
                 "writes it to stdout and the table to stderr (default: the JSON to stdout)");
  app.add_option("--allan-csv", o->allan_csv, "also write the Allan curves as CSV here");
  app.add_option("--budget", o->budget,
                 "evaluate this uncertainty budget (docs/budget-format.md); its session inputs "
                 "refer to SESSION")
      ->check(CLI::ExistingFile);
  app.add_option("--html", o->html,
                 "also write a self-contained HTML report with plots here (docs/reports.md)");
  app.add_option("--export", o->export_format,
                 "with --allan: also write the noise terms as this estimator's noise file: "
                 "kalibr, openvins, basalt, vins, orbslam3, gtsam, px4-ekf2, ros "
                 "(docs/noise.md; characterize noise-export has their options)")
      ->check(CLI::IsMember(NoiseExportFormatNames()));
  app.add_option("--export-file", o->export_file, "the noise file of --export (atomically)");
  AddAxisReductionOption(&app, &o->export_options.reduction,
                         "with --export: one value over the three axes, max (the largest axis "
                         "and its u) or rms");
  app.add_option("--spec-part", o->spec_part,
                 "with --allan: judge N, B, K against this part's datasheet figures "
                 "(MPU6050, MPU9250, ICM20948, ICM42688P, ...; docs/specs.md): a JCGM 106 "
                 "decision for max/min figures, ratio and E_n for typ ones");
  app.add_option("--spec-library", o->spec_library, "the spec library (datasets/specs/specs.json)")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--spec-rule", o->spec_rule,
                 "with --spec-part: the JCGM 106 decision rule for max/min figures")
      ->check(CLI::IsMember({"simple", "guarded", "risk"}))
      ->capture_default_str();
  if (accuracy) AddAccuracyOptions(app, &o->accuracy);
  app.add_option("--threads", o->threads, "worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  if (accuracy) {
    app.add_flag("--stream", o->stream,
                 "read the record once in groups and evaluate each quantity from a temporary "
                 "file (memory independent of the length; docs/streaming.md)");
    app.add_option("--stream-above-memory-share", o->stream_above_memory_share,
                   "stream by itself when the file is larger than this share of the available "
                   "memory (0: never)")
        ->check(CLI::Range(0.0, 100.0))
        ->default_str("0.5");
    app.add_option("--stream-group-bytes", o->stream_group_bytes,
                   "with --stream: bytes of the file read per group of rows (memory is about 3 "
                   "to 15 times this, the more the narrower the rows)")
        ->check(CLI::PositiveNumber)
        ->default_str("8388608");
  }
}

void AddAnalyzeOptions(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  AddTypeAOptions(app, o.get(), /*accuracy=*/true);
  app.callback([&app, o, exit_code] {
    if (!app.get_subcommands().empty()) return;
    if (o->session.empty()) {
      apps::PrintText(stderr, fmt::format("error: no session given\n{}", app.help()));
      *exit_code = kExitUsage;
      return;
    }
    if (Status s = CheckModeOptions(GivenOn(app), *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

void AddAnalyzeCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<AnalyzeOptions>();
  CLI::App* sub = app.add_subcommand(
      "analyze",
      "GUM Type A evaluation of every quantity per tag, with --allan the noise terms, with "
      "--budget a budget on the session (also: characterize SESSION --type-a ...)");
  AddTypeAOptions(*sub, o.get(), /*accuracy=*/false);
  sub->callback([sub, o, exit_code] {
    if (Status s = CheckModeOptions(GivenOn(*sub), *o); !s.ok()) {
      *exit_code = PrintErrorExit(s.error());
      return;
    }
    *exit_code = RunAnalyze(*o);
  });
}

void AddConvertCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ConvertOptions>();
  CLI::App* sub = app.add_subcommand(
      "convert",
      "turn any readable session (receiver capture, EuRoC, raw prints, phyphox, Sensor Logger, PX4 "
      "ULog, MCAP, ROS 1 and ROS 2 bags, imu_tk's two files) into canonical session.csv; several "
      "files are joined on time");
  sub->add_option("inputs", o->inputs,
                  "INPUT, several files of one recording (joined on time), or ACC GYRO with "
                  "--imutk; - reads stdin")
      ->required()
      ->check(ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "session.csv to write (- for stdout)")->required();
  // The load flags, --format among them, as every command that loads a session has them.
  AddLoadCliOptions(sub, &o->load);
  CLI::Option* format = sub->get_option("--format");
  CLI::Option* imutk =
      sub->add_flag("--imutk", o->imutk, "the inputs are imu_tk's two files: ACC GYRO")
          ->excludes(format);
  sub->add_option("--from", o->from, "the older spelling of --format (--from imutk: --imutk)")
      ->check(CLI::IsMember({"auto", "receiver", "csv", "imutk", "euroc", "raw", "phyphox",
                             "sensorlogger", "phone", "ulog"}))
      ->excludes(format)
      ->excludes(imutk);
  sub->callback([o, exit_code] { *exit_code = RunConvert(*o); });
}

void AddThermalSimulateOptions(CLI::App* sub, SimulateOptions* o) {
  ThermalSimulationOptions& t = o->thermal;
  sub->add_option("--thermal-profile", o->thermal_profile,
                  "thermal: ramp (chamber ramp), steps (chamber steps) or warmup (power-on)")
      ->check(CLI::IsMember({"ramp", "steps", "warmup"}))
      ->capture_default_str();
  sub->add_option("--temp-low-c", t.temp_low_c, "thermal: lowest temperature")
      ->capture_default_str();
  sub->add_option("--temp-high-c", t.temp_high_c, "thermal: highest temperature")
      ->capture_default_str();
  sub->add_option("--ramp-s", t.ramp_s, "thermal: ramp duration (one leg)")->capture_default_str();
  sub->add_option("--steps", t.steps, "thermal: chamber levels")->capture_default_str();
  sub->add_option("--step-dwell-s", t.step_dwell_s, "thermal: time at each level")
      ->capture_default_str();
  sub->add_option("--step-tau-s", t.step_tau_s, "thermal: die time constant after a step")
      ->capture_default_str();
  sub->add_option("--warmup-tau-s", t.warmup_tau_s, "thermal: warm-up time constant")
      ->capture_default_str();
  sub->add_option("--warmup-s", t.warmup_s, "thermal: warm-up record length")
      ->capture_default_str();
  sub->add_flag("--cooling-leg", t.cooling_leg, "thermal: return from high to low (ramp, steps)");
  sub->add_option("--bias-order", t.bias_order, "thermal truth: bias polynomial order")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  sub->add_option("--accel-excursion-g", t.accel_excursion_g,
                  "thermal truth: accel bias excursion scale over the span")
      ->capture_default_str();
  sub->add_option("--gyro-excursion-dps", t.gyro_excursion_dps,
                  "thermal truth: gyro bias excursion scale over the span")
      ->capture_default_str();
  sub->add_option("--accel-hysteresis-g", t.accel_hysteresis_g,
                  "thermal truth: heating minus cooling accel bias (needs --cooling-leg)")
      ->capture_default_str();
  sub->add_option("--gyro-hysteresis-dps", t.gyro_hysteresis_dps,
                  "thermal truth: heating minus cooling gyro bias (needs --cooling-leg)")
      ->capture_default_str();
  sub->add_option("--temp-glitches", t.temp_glitches,
                  "thermal: isolated temperature read errors (+40 degC) at random rows")
      ->capture_default_str();
}

void AddSimulateCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "write a static tag session with known truth (docs/simulator.md)");
  sub->add_option("-o,--output", o->output, "file to write (- for stdout)")->required();
  sub->add_option("--format", o->format, "csv or receiver")
      ->check(CLI::IsMember({"csv", "receiver"}))
      ->capture_default_str();
  sub->add_option("--columns", o->columns,
                  "session.csv columns: angles (qw..qz), imu (ax_g..gz_dps, temp_c) or all")
      ->check(CLI::IsMember({"angles", "imu", "all"}))
      ->capture_default_str();
  sub->add_option("--seed", o->sim.seed, "random seed")->capture_default_str();
  sub->add_option("--sensor", o->sim.sensors, "a tag that sends (repeatable; default 2)");
  sub->add_option("--tags", o->tags, "tags 1..N send (instead of --sensor)")
      ->check(CLI::Range(1, 255));
  sub->add_option("--never", o->sim.never_sensors, "a tag that never connects (repeatable)");
  sub->add_option("--duration-s", o->sim.duration_s, "length in seconds")->capture_default_str();
  sub->add_option("--rate-hz", o->sim.rate_hz,
                  "session.csv sample rate (default: one sample per 0.10013 s frame)");
  sub->add_option("--packet-loss", o->sim.packet_loss, "probability a frame has no new packet")
      ->capture_default_str();
  sub->add_option("--transient-tau-s", o->sim.transient_tau_s,
                  "time constant of the start-up transient")
      ->capture_default_str();
  sub->add_option("--yaw-drift-dps", o->sim.yaw_drift_dps, "yaw drift rate")->capture_default_str();
  sub->add_option("--kind", o->kind,
                  "static; table: a rotation-table sweep; calibration: a multi-pose calibration "
                  "session in raw LSB; thermal: one pose over a temperature profile in raw LSB "
                  "(docs/simulator.md)")
      ->check(CLI::IsMember({"static", "table", "calibration", "thermal"}))
      ->capture_default_str();
  sub->add_option("--poses", o->calibration.poses,
                  "calibration: static poses (cube faces, corners, edges, cycled)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sub->add_option("--accel-cross-axis", o->calibration.accel_cross_axis,
                  "calibration: the accelerometer's cross-axis terms are drawn uniform in +- this "
                  "(0.02 = the MPU6050 datasheet's 2 %; 0 = none)")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  sub->add_option("--gyro-cross-axis", o->calibration.gyro_cross_axis,
                  "calibration: the gyroscope's cross-axis terms are drawn uniform in +- this")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  sub->add_option("--pose-dwell-s", o->calibration.dwell_s,
                  "calibration: still time per pose (the first twice as long)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--move-s", o->calibration.move_s,
                  "calibration: duration of each hand rotation between poses")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--run-rate-dps", o->calibration.table_rates_dps,
                  "calibration: a rate-table run at every pose, logger running (repeatable; "
                  "default 90)");
  sub->add_option("--run-s", o->calibration.table_run_s, "calibration: length of each table run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--temp-start-c", o->calibration.temp_start_c,
                  "calibration: temperature ramp start")
      ->capture_default_str();
  sub->add_option("--temp-end-c", o->calibration.temp_end_c, "calibration: temperature ramp end")
      ->capture_default_str();
  sub->add_flag("--no-temperature", o->no_temperature,
                "calibration: no temp_c column and no temperature terms in the truth");
  sub->add_option("--table-axis", o->table_axis, "table: the tag axis turned (yaw, pitch, roll)")
      ->capture_default_str();
  sub->add_option("--table-start-deg", o->table.start_deg, "table: first plateau angle")
      ->capture_default_str();
  sub->add_option("--table-end-deg", o->table.end_deg, "table: last plateau angle")
      ->capture_default_str();
  sub->add_option("--table-step-deg", o->table.step_deg, "table: step between plateaus")
      ->capture_default_str();
  sub->add_option("--sweeps", o->table.sweeps, "table: up-and-down sweeps")->capture_default_str();
  sub->add_option("--dwell-s", o->table.dwell_s, "table: dwell per plateau")->capture_default_str();
  sub->add_option("--table-rate-dps", o->table.move_rate_dps, "table: rate between plateaus")
      ->capture_default_str();
  sub->add_option("--offset-deg", o->table.offset_deg, "table truth: error offset")
      ->capture_default_str();
  sub->add_option("--scale-error", o->table.scale_error, "table truth: scale error (deg/deg)")
      ->capture_default_str();
  sub->add_option("--cos1-deg", o->table.cos1_deg, "table truth: misalignment cos(theta) term")
      ->capture_default_str();
  sub->add_option("--sin1-deg", o->table.sin1_deg, "table truth: misalignment sin(theta) term")
      ->capture_default_str();
  sub->add_option("--hysteresis-deg", o->table.hysteresis_deg, "table truth: up minus down")
      ->capture_default_str();
  sub->add_option("--tilt-deg", o->table.tilt_deg, "table truth: cross-axis mounting tilt")
      ->capture_default_str();
  sub->add_option("--noise-deg", o->table.noise_std_deg, "table truth: noise std (AR(1))")
      ->capture_default_str();
  sub->add_option("--lag-tau-s", o->table.lag_tau_s, "table truth: tag response time constant")
      ->capture_default_str();
  sub->add_option("--reference-output", o->reference_output,
                  "table: write the reference as a separate log (t_s, table_angle_deg) here");
  sub->add_option("--reference-offset-s", o->table.reference_clock_offset_s,
                  "table: the reference log's clock runs this far ahead")
      ->capture_default_str();
  sub->add_option("--truth-output", o->truth_output,
                  "table, calibration: the truth as JSON (default: OUTPUT.truth.json when -o is a "
                  "file)");
  sub->add_option("--table-readout", o->table_readout,
                  "table: continuous (0..360 as turned) or wrap180 (signed, (-180, 180])")
      ->check(CLI::IsMember({"continuous", "wrap180"}))
      ->capture_default_str();
  sub->add_flag("--table-pitch-through-90", o->table.pitch_through_90,
                "table: let a pitch table pass +-90 deg (the tag's Euler pitch folds there)");
  sub->add_flag("--table-up-only", o->table.up_only,
                "table: one pass up, no down pass (hysteresis not measured; --sweeps 1)");
  sub->add_option("--noise-ar1", o->table.noise_ar1,
                  "table truth: lag-1 correlation of the noise per frame")
      ->capture_default_str();
  AddThermalSimulateOptions(sub, o.get());
  sub->callback([o, exit_code] { *exit_code = RunSimulate(*o); });
}

void AddBudgetCommand(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<BudgetOptions>();
  // Budget files may name sessions; they are evaluated in full (no window).
  options->session_resolver = MakeSessionQuantityResolver("", {}, {});
  CLI::App* sub = app.add_subcommand(
      "budget", "Evaluate an uncertainty budget (GUM + JCGM 101 Monte Carlo) from a JSON file");
  sub->add_option("BUDGET", options->budget_path, "Budget file (docs/budget-format.md)")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("-o,--output", options->output_path,
                  "Write the metro.budget-report/1 JSON here and print the table; -o - "
                  "writes it to stdout and the table to stderr");
  sub->add_option("--html", options->html_path,
                  "Also write the budget page here: the statement, both coverage intervals, the "
                  "GUF validation, the Monte Carlo histogram with the GUF density, the "
                  "contributions (docs/reports.md, \"Budget page\"); - for stdout");
  sub->callback([options, exit_code] { *exit_code = RunBudget(*options); });
}

void AddBatchCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<BatchCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "batch",
      "analyse many sessions in parallel: one JSON report each, summary.json and a summary "
      "table per tag and quantity; a failing session is named and the others go on");
  sub->add_option("inputs", o->inputs,
                  "session files, directories (their *.csv and *.txt) or glob patterns")
      ->required();
  sub->add_option("-o,--output-dir", o->output_dir, "directory for the reports (created)")
      ->required();
  sub->add_option("--jobs", o->jobs, "sessions in parallel (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--html", o->html,
                  "also write the batch page here (- for stdout): a row per session and tag with "
                  "dead tags marked, spread plots per quantity, links to each session's page, "
                  "written beside its JSON report (docs/reports.md, \"Batch page\")");
  sub->add_flag("--type-a", o->type_a, "GUM Type A evaluation (always done)");
  AddAnalysisCliOptions(sub, &o->analysis);
  sub->callback([o, exit_code] { *exit_code = RunBatchCommand(*o); });
}

void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "report",
      "render a saved JSON (metro.report/1, metro.calibration/1, metro.accuracy-report/1, any "
      "other schema as tables) "
      "as a self-contained HTML page");
  sub->add_option("json", o->json, "REPORT.json")->required()->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "HTML file to write (- for stdout)")->required();
  sub->add_option("--session", o->session,
                  "accepted for older scripts and not used: a page is drawn from the report alone "
                  "(its plot data), no input is reloaded")
      ->check(CLI::ExistingFile);
  sub->add_option("--tags,--tag-registry", o->tags,
                  "tags file naming the tags on the page (docs/formats.md \"Tags file\"): a "
                  "session report's sensors, a calibration.json's tags (name, device_id, profile)")
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunReportCommand(*o); });
}

void AddCaptureCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<CaptureCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "capture", "record the central receiver's serial stream, with a live per-tag view");
  sub->add_option("--port", o->port, "the receiver's serial port, e.g. /dev/ttyACM0")->required();
  sub->add_option("--baud", o->baud, "baud rate (8N1, raw)")->capture_default_str();
  sub->add_option("--duration-s", o->duration_s, "stop after this many seconds (0: at Ctrl-C)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("-o,--output", o->output,
                  "the capture file (never replaced without --force); with --analyze: the "
                  "JSON report");
  sub->add_option("--capture", o->capture, "the capture file when -o names the report");
  sub->add_flag("--force", o->force, "replace an existing capture file");
  CLI::Option* on = sub->add_flag(
      "--reconnect", o->reconnect,
      "reopen the port when it returns after an unplug (default without --duration-s)");
  sub->add_flag("--no-reconnect", o->no_reconnect,
                "finish the capture when the port disappears (default with --duration-s)")
      ->excludes(on);
  sub->add_option("--frame-period-s", o->frame_period_s,
                  "the receiver's frame period for the live statistics and --analyze")
      ->capture_default_str();
  sub->add_flag("--analyze", o->analyze,
                "then the full Type A report of the capture (--settle auto)");
  sub->add_option("--tags,--tag-registry", o->tags,
                  "tags file naming the tags (docs/formats.md \"Tags file\"): below the live "
                  "view and the final table, and in the --analyze report")
      ->check(CLI::ExistingFile);
  sub->callback([o, exit_code] { *exit_code = RunCaptureCommand(*o); });
}

void AddNoiseExportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<NoiseExportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "noise-export",
      "write a report's IEEE 952 noise terms as an estimator's noise file (kalibr, openvins, "
      "basalt, vins, orbslam3, gtsam, px4-ekf2, ros), each value's convention and u beside it");
  sub->add_option("report", o->common.report, "REPORT.json made with --allan")
      ->check(CLI::ExistingFile);
  sub->add_option_function<std::string>(
         "--to",
         [o](const std::string& value) {
           Result<NoiseExportFormat> f = ParseNoiseExportFormat(value);
           if (!f.ok()) throw CLI::ValidationError("--to", f.error().message);
           o->common.library.format = f.value();
         },
         "kalibr, openvins, basalt, vins, orbslam3, gtsam, px4-ekf2 or ros")
      ->required();
  sub->add_option("-o,--output", o->output, "the file to write (atomically; default -: stdout)");
  AddNoiseExportCliOptions(sub, &o->common);
  sub->add_option("--from-spec", o->from_spec,
                  "instead of REPORT: a part's datasheet noise figures as Kalibr's imu.yaml, "
                  "assumptions stated in the file (docs/specs.md)");
  sub->add_option("--spec-library", o->spec_library, "the spec library")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  sub->add_option("--spec-source", o->spec.source,
                  "with --from-spec: the document of the part (default: its first datasheet)");
  sub->add_option("--update-rate-hz", o->spec.update_rate_hz,
                  "with --from-spec: the rate the IMU is read at (Kalibr's update_rate)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--partial", o->spec.partial,
                "with --from-spec: write the file without the K keys the datasheet cannot give "
                "(Kalibr will not read it as is)");
  sub->callback([o, exit_code] { *exit_code = RunNoiseExport(*o); });
}

void AddNoiseCompareCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<NoiseCompareOptions>();
  CLI::App* sub = app.add_subcommand(
      "noise-compare",
      "read an estimator's noise file (any noise-export format) and compare each value with a "
      "report's measurement: ratio and E_n");
  sub->add_option("file", o->file, "imu.yaml, a VINS/ORB-SLAM3 config, PX4 params, ...")
      ->check(CLI::ExistingFile);
  sub->add_option("report", o->common.report, "REPORT.json made with --allan")
      ->check(CLI::ExistingFile);
  sub->add_option("--spec-part", o->spec_part,
                  "instead of FILE REPORT: the part's published noise figures (datasheet, "
                  "EuRoC's sensor.yaml, Kalibr's sample) side by side, with ratios "
                  "(docs/specs.md)");
  sub->add_option("--spec-library", o->spec_library, "the spec library")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  sub->add_option("--reference", o->reference,
                  "with --spec-part: the document the ratios are to (default: the first)");
  sub->add_option("--format", o->format, "the file's format (default: told by its keys)")
      ->check(CLI::IsMember(NoiseExportFormatNames()));
  AddNoiseExportCliOptions(sub, &o->common);
  sub->callback([o, exit_code] { *exit_code = RunNoiseCompare(*o); });
}

void AddTopicsCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<TopicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "topics",
      "list the topics of a PX4 ULog (name, multi id, messages, message size, rate, dropouts, "
      "appended data) or of an MCAP file, a ROS 1 bag or a ROS 2 bag folder (topic, message "
      "type, messages, rate, chunks); choose IMU topics with --topic");
  sub->add_option("file", o->file,
                  "a PX4 ULog (.ulg), an MCAP file (.mcap), a ROS 1 bag (.bag) or a ROS 2 bag "
                  "folder (or its metadata.yaml)")
      ->required()
      ->check(CLI::ExistingPath);
  sub->add_flag("--lenient", o->lenient,
                "read the complete messages of a truncated file, counting the loss");
  sub->callback([o, exit_code] { *exit_code = RunTopics(*o); });
}

}  // namespace
}  // namespace metro::apps

int main(int argc, char** argv) {
  // SIGINT/SIGTERM remove the temporaries of outputs being written; SIGXFSZ is ignored.
  metro::InstallInterruptCleanup();
  CLI::App app{"metro characterize: uncertainty evaluation of IMU sensor-tag sessions"};
  app.require_subcommand(0, 1);
  int exit_code = metro::apps::kExitOk;
  metro::apps::AddAnalyzeOptions(app, &exit_code);  // characterize SESSION --type-a|--accuracy
  metro::apps::AddAnalyzeCommand(app, &exit_code);
  metro::apps::AddAccuracyCommand(app, &exit_code);
  metro::apps::AddConvertCommand(app, &exit_code);
  metro::apps::AddSimulateCommand(app, &exit_code);
  metro::apps::AddBudgetCommand(app, &exit_code);
  metro::apps::AddBatchCommand(app, &exit_code);
  metro::apps::AddReportCommand(app, &exit_code);
  metro::apps::AddCaptureCommand(app, &exit_code);
  metro::apps::AddNoiseExportCommand(app, &exit_code);
  metro::apps::AddNoiseCompareCommand(app, &exit_code);
  metro::apps::AddTopicsCommand(app, &exit_code);
  metro::apps::AddVersionFlag(app, "characterize");
  metro::apps::AddQuietFlag(app);  // On the app and every subcommand (docs/unix.md).
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return metro::apps::FinishStdout(code == 0 ? 0 : metro::apps::kExitUsage);
  } catch (const std::bad_alloc&) {
    // The loaders turn this into an error naming the file; anything else that runs out.
    std::fputs("error: out of memory\n", stderr);
    return metro::apps::kExitFailed;
  }
  return metro::apps::FinishStdout(exit_code);
}
