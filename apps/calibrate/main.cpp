// calibrate: accelerometer and gyroscope calibration with the uncertainty of every constant.
// The command line: every subcommand's flags bound to its options struct (*_command.hpp) and
// its Run function as the callback. This is the program's one translation unit that includes
// CLI11 (issue #39: CLI11 is header-only and costs seconds of compile time per file); the work
// is done by the commands and the metro library (metro/calibration/).
#include <cstdio>
#include <memory>
#include <new>

#include "apply_command.hpp"
#include "blob_command.hpp"
#include "cli_flags.hpp"
#include "commands.hpp"
#include "conformity_cli.hpp"
#include "export_command.hpp"
#include "fit_command.hpp"
#include "import_command.hpp"
#include "inspect_command.hpp"
#include "push_command.hpp"
#include "registry_command.hpp"
#include "registry_hooks.hpp"
#include "report_command.hpp"
#include "tags_cli.hpp"

namespace metro::calibrate_app {
namespace {

void AddTagsOption(CLI::App* sub, std::string* tags) {
  sub->add_option("--tags,--tag-registry", *tags,
                  "tags file: per sensor its name, device_id (either word order) and profile "
                  "(docs/formats.md \"Tags file\")")
      ->check(CLI::ExistingFile);
}

// --profile mpu6050|generic, --accel-fs-g G, --gyro-fs-dps D of `blob` and `push`: the nominal
// sensitivity a blob section declares (metro::blob::SensorProfile, docs/calibration-blob.md 10).
void AddSensorProfileOptions(CLI::App* sub, std::string* profile, std::optional<double>* accel_fs_g,
                             std::optional<double>* gyro_fs_dps) {
  sub->add_option("--profile", *profile,
                  "the IMU: mpu6050 (its datasheet sensitivity at the declared or matching "
                  "full-scale setting) or generic (another IMU: 32768 / the declared full scale, "
                  "else the calibration's own); default: the tags file's, else mpu6050")
      ->check(CLI::IsMember({"mpu6050", "generic"}));
  sub->add_option("--accel-fs-g", *accel_fs_g,
                  "declared accelerometer full scale [g] (mpu6050: 2, 4, 8 or 16; default: the "
                  "setting M matches)");
  sub->add_option("--gyro-fs-dps", *gyro_fs_dps,
                  "declared gyroscope full scale [deg/s] (mpu6050: 250, 500, 1000 or 2000; "
                  "default: the setting M matches)");
}

void AddRegistryOptions(CLI::App* sub, RegistryCliOptions* o) {
  sub->add_option("--registry", o->url,
                  "record this in the calibration registry: a SQLite file or "
                  "postgresql://... (default: $METRO_REGISTRY; docs/registry.md)");
  sub->add_option("--station", o->station, "station name recorded with a calibration");
  sub->add_option("--operator", o->operator_name, "operator recorded with a calibration");
}

void AddSpecOptions(CLI::App* sub, SpecCliOptions* o) {
  sub->add_option("--spec", o->spec,
                  "SPEC.json: tolerance limits per constant and a decision rule; writes a "
                  "statement of conformity (docs/conformity.md)")
      ->check(CLI::ExistingFile);
  sub->add_flag("--fail-on-nonconformity", o->fail_on_nonconformity,
                "exit 1 when any constant's decision is fail (with --spec)");
}

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

void AddApplyCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ApplyOptions>();
  CLI::App* sub = app.add_subcommand(
      "apply",
      "write a session with calibrated ax_g.. and gx_dps.. columns (all rows and "
      "columns kept)");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("session", o->inputs, "SESSION (or ACC GYRO with --imutk); - reads stdin")
      ->required()
      ->check(apps::ExistingFileOrStdin());
  sub->add_option("-o,--output", o->output, "calibrated session.csv to write (- for stdout)")
      ->required();
  sub->add_flag("--imutk", o->imutk, "the session is an imu_tk pair: ACC GYRO");
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range, as given to calibrate blob "
                  "(default: the fitted span - 5 degC)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  AddRegistryOptions(sub, &o->registry);
  AddTagsOption(sub, &o->tags);
  sub->callback([o, exit_code] { *exit_code = RunApply(*o); });
}

void AddReportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* sub = app.add_subcommand("report", "print a readable summary of calibration.json");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--html", o->html, "also write the calibration certificate (HTML) here");
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "certify constants marked model_rejected (a model the data reject or an exact "
                "fit), with that notice on the certificate");
  AddTagsOption(sub, &o->tags);
  sub->callback([o, exit_code] { *exit_code = RunReport(*o); });
}

void AddBlobCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<BlobOptions>();
  CLI::App* sub = app.add_subcommand(
      "blob",
      "write a tag's calibration blob (docs/calibration-blob.md) and, with --hex, the Intel "
      "HEX for nrfjprog");
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--sensor", o->sensor, "the tag in calibration.json (or --all)");
  sub->add_option("--device-id", o->device_id,
                  "the tag's FICR DEVICEID: 16 hex digits DEVICEID[1] then DEVICEID[0], or the "
                  "two words nrfjprog --memrd 0x10000060 --n 8 prints (DEVICEID[0] DEVICEID[1]), "
                  "with or without 0x (default: the tags file's, else calibration.json's)");
  AddTagsOption(sub, &o->tags);
  sub->add_flag("--all", o->all,
                "every tag of calibration.json: -o names a directory, DIR/tag<N>.bin and .hex, "
                "device IDs from --tags or calibration.json");
  sub->add_option("--seq", o->seq, "blob sequence number, 1..4294967294 (default 1)")
      ->check(CLI::Range(1u, 0xFFFFFFFEu));
  sub->add_option("-o,--output", o->output,
                  "tag.bin to write (- for stdout, not a terminal); with --all a directory")
      ->required();
  sub->add_option("--hex", o->hex,
                  "also write this Intel HEX: blob at slot A, tombstone at B (- for stdout)");
  sub->add_option("--slot-address", o->slot_address,
                  "slot A address in the HEX (default 0x3B000); slot B is the next page");
  sub->add_option("--dlpf-cfg", o->dlpf_cfg, "the tag firmware's MPU6050 DLPF_CFG (default 3)")
      ->check(CLI::Range(0, 6));
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range the tag clamps to (default: the "
                  "fitted span - 5 degC; lower is extrapolation, with a warning)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  AddSensorProfileOptions(sub, &o->profile, &o->accel_fs_g, &o->gyro_fs_dps);
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "write constants calibration.json marks model_rejected (a model the data reject "
                "or an exact fit; docs/calibration-model.md) anyway");
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code] { *exit_code = RunBlobCommand(*o); });
}

void AddInspectCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<InspectCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "inspect",
      "decode and validate a calibration blob (.bin) or programmer image (.hex) with the tag "
      "firmware's rules; exit 0 valid, 1 no valid calibration, 2 unreadable");
  sub->add_option("file", o->input, "tag.bin or tag.hex")->required()->check(CLI::ExistingFile);
  sub->add_option("--device-id", o->device_id,
                  "check against this tag (16 hex digits DEVICEID[1] DEVICEID[0], or nrfjprog "
                  "--memrd's words DEVICEID[0] DEVICEID[1]); default: each blob's own id");
  AddTagsOption(sub, &o->tags);
  sub->add_option("--sensor", o->sensor,
                  "with --tags: check the blob against this tag's device_id");
  sub->add_option("--slot-address", o->slot_address,
                  "slot A address in a .hex (default 0x3B000); slot B is the next page");
  sub->add_flag("--json", o->json, "print JSON instead of text");
  sub->callback([o, exit_code] { *exit_code = RunInspect(*o); });
}

void AddPushCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<PushCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "push",
      "send a tag's calibration over the central's serial link (230400 8N1) with the push "
      "protocol, then read it back");
  sub->add_option("--port", o->port, "serial device of the BLE central, e.g. /dev/ttyACM0")
      ->required();
  sub->add_option("calibration", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--sensor", o->sensor, "the tag in calibration.json (or --all)");
  sub->add_option("--device-id", o->device_id,
                  "the tag's FICR DEVICEID (16 hex digits DEVICEID[1] DEVICEID[0], or nrfjprog "
                  "--memrd's two words DEVICEID[0] DEVICEID[1]); another tag is refused. "
                  "Default: the tags file's, else calibration.json's");
  AddTagsOption(sub, &o->tags);
  sub->add_flag("--all", o->all,
                "every tag of calibration.json, each to its device (--tags or calibration.json), "
                "read back, then a table (sensor, name, device, result)");
  sub->add_flag("--any-device", o->any_device,
                "no device ID is known: write to whichever tag answers (else refused)");
  sub->add_option("--seq", o->seq, "blob seq (default: the tag's active seq + 1)")
      ->check(CLI::Range(1u, 0xFFFFFFFEu));
  sub->add_option("--dlpf-cfg", o->dlpf_cfg, "the tag firmware's MPU6050 DLPF_CFG (default 3)")
      ->check(CLI::Range(0, 6));
  sub->add_option("--t-valid-min-c", o->t_valid_min_c,
                  "lower end of the temperature validity range the tag clamps to (default: the "
                  "fitted span - 5 degC; lower is extrapolation, with a warning)");
  sub->add_option("--t-valid-max-c", o->t_valid_max_c,
                  "upper end of the temperature validity range (default: the fitted span + 5 "
                  "degC)");
  sub->add_option("--timeout-ms", o->timeout_ms, "wait for each answer (default 1000)")
      ->check(CLI::Range(1, 60000));
  sub->add_option("--retries", o->retries, "resends of one request (default 5)")
      ->check(CLI::Range(0, 100));
  AddSensorProfileOptions(sub, &o->profile, &o->accel_fs_g, &o->gyro_fs_dps);
  sub->add_flag("--accept-rejected-model", o->accept_rejected_model,
                "send constants calibration.json marks model_rejected (a model the data reject "
                "or an exact fit; docs/calibration-model.md) anyway");
  AddRegistryOptions(sub, &o->registry);
  sub->callback([o, exit_code] { *exit_code = RunPushCommand(*o); });
}

void AddRegistryCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<RegistryQueryOptions>();
  CLI::App* reg = app.add_subcommand(
      "registry", "query the calibration registry: history, drift, due, export (docs/registry.md)");
  reg->require_subcommand(1);
  auto url = [&](CLI::App* sub) {
    sub->add_option("--registry", o->url,
                    "the registry: a SQLite file or postgresql://... (default: $METRO_REGISTRY)");
  };
  CLI::App* history = reg->add_subcommand("history", "every calibration of a device, oldest first");
  url(history);
  history->add_option("--device-id", o->device_id, "the tag's device ID (16 hex digits)")
      ->required();
  history->add_flag("--json", o->json, "JSON: {\"device_id\", \"calibrations\": [...]}");
  history->callback([o, exit_code] { *exit_code = RunRegistryHistory(*o); });

  CLI::App* drift = reg->add_subcommand(
      "drift", "change of each constant between a device's last two calibrations, with E_n");
  url(drift);
  drift->add_option("--device-id", o->device_id, "the tag's device ID (16 hex digits)")->required();
  drift->add_flag("--json", o->json, "JSON: {\"device_id\", \"constants\": [...]}");
  drift->callback([o, exit_code] { *exit_code = RunRegistryDrift(*o); });

  CLI::App* due = reg->add_subcommand("due", "devices whose recalibration interval has run out");
  url(due);
  due->add_option("--interval-days", o->interval_days,
                  "recalibration interval [days] (default 365)");
  due->add_option("--at", o->at_utc, "judge at this ISO 8601 UTC time (default now)");
  due->add_flag("--all", o->all, "list every device with its due date");
  due->add_flag("--json", o->json,
                R"(JSON: {"at_utc", "interval_days", "devices": [{"device_id", "due", ...}]})");
  due->callback([o, exit_code] { *exit_code = RunRegistryDue(*o); });

  CLI::App* exported = reg->add_subcommand("export",
                                           "every calibration as CSV (one row per constant) "
                                           "or JSON");
  url(exported);
  exported->add_option("--format", o->format, "csv or json")->check(CLI::IsMember({"csv", "json"}));
  exported->add_option("-o,--output", o->output, "file to write (default - : stdout)");
  exported->callback([o, exit_code] { *exit_code = RunRegistryExport(*o); });
}

void AddExportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ExportCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "export",
      "write a tag's constants as an autopilot's parameters (PX4 CAL_ACCn_/CAL_GYROn_, ArduPilot "
      "INS_ACC*/INS_GYR*) or an estimator's intrinsics (Kalibr, OpenVINS, basalt, librealsense); "
      "what the form cannot hold is named (docs/calibration-interchange.md)");
  sub->add_option("CALIBRATION", o->calibration, "calibration.json")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--to", o->to,
                  "px4 (QGroundControl .params), ardupilot (.param), kalibr (imu-chain yaml), "
                  "openvins (kalibr_imu_chain.yaml), basalt (calibration.json keys), realsense "
                  "(rs-imu-calibration's calibration.json)")
      ->required();
  sub->add_option("--sensor", o->options.sensor, "the tag in calibration.json")->required();
  sub->add_option("--instance", o->options.instance,
                  "the autopilot's IMU index (PX4 0..3: CAL_ACC<i>_; ArduPilot 0..2: INS_ACC, "
                  "INS_ACC2, INS_ACC3; default 0); kalibr/openvins: imu<i>; realsense: imus[i]");
  sub->add_option("--px4-accel-device-id", o->options.px4_accel_device_id,
                  "PX4's device ID of the accelerometer (CAL_ACCn_ID; PX4 applies the values "
                  "only to that device)");
  sub->add_option("--px4-gyro-device-id", o->options.px4_gyro_device_id,
                  "PX4's device ID of the gyroscope (CAL_GYROn_ID)");
  sub->add_option("--covariance", o->covariance,
                  "the covariance sidecar to write (default for kalibr, openvins, basalt, "
                  "realsense: FILE.covariance.json; px4, ardupilot: only when given)");
  sub->add_option("-o,--output", o->output, "the file to write (- for stdout)")->required();
  sub->callback([o, exit_code] { *exit_code = RunExport(*o); });
}

void AddImportCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<ImportCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "import",
      "read another tool's intrinsics (Kalibr, OpenVINS, basalt, librealsense, PX4, ArduPilot) "
      "as calibration.json; what the format did not carry and implausible constants are named "
      "(docs/calibration-interchange.md)");
  sub->add_option("FILE", o->file, "the tool's file")->required()->check(CLI::ExistingFile);
  sub->add_option("--from", o->from, "kalibr, openvins, basalt, realsense, px4 or ardupilot")
      ->required();
  sub->add_option("--instance", o->instance,
                  "imu<i> (kalibr, openvins), imus[i] (realsense), the autopilot's IMU index "
                  "(default 0)");
  sub->add_option("--sensor", o->sensor, "the tag number calibration.json gets (default 1)");
  sub->add_option("--covariance", o->covariance,
                  "the covariance sidecar (default FILE.covariance.json when it exists; "
                  "without one the uncertainties are unknown)");
  sub->add_option("-o,--output", o->output, "calibration.json to write (default - for stdout)");
  sub->callback([o, exit_code] { *exit_code = RunImport(*o); });
}

}  // namespace
}  // namespace metro::calibrate_app

int main(int argc, char** argv) {
  // SIGINT/SIGTERM remove the temporaries of outputs being written; SIGXFSZ is ignored.
  metro::InstallInterruptCleanup();
  namespace app_ns = metro::calibrate_app;
  CLI::App app{"metro calibrate: IMU calibration (bias, scale, misalignment) with uncertainties"};
  app.require_subcommand(1);
  int exit_code = app_ns::kExitOk;
  app_ns::AddFitCommand(app, &exit_code);
  app_ns::AddApplyCommand(app, &exit_code);
  app_ns::AddReportCommand(app, &exit_code);
  app_ns::AddBlobCommand(app, &exit_code);
  app_ns::AddInspectCommand(app, &exit_code);
  app_ns::AddPushCommand(app, &exit_code);
  app_ns::AddRegistryCommand(app, &exit_code);
  app_ns::AddExportCommand(app, &exit_code);
  app_ns::AddImportCommand(app, &exit_code);
  metro::apps::AddVersionFlag(app, "calibrate");
  metro::apps::AddQuietFlag(app);  // On the app and every subcommand (docs/unix.md).
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return metro::apps::FinishStdout(code == 0 ? 0 : app_ns::kExitUsage);
  } catch (const std::bad_alloc&) {
    // The loaders turn this into an error naming the file; anything else that runs out.
    std::fputs("error: out of memory\n", stderr);
    return app_ns::kExitFailed;
  }
  return metro::apps::FinishStdout(exit_code);
}
