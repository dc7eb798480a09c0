// characterize simulate -o FILE [--format csv|receiver] [--seed N] [--sensor N]... ...
#include "simulate_command.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <optional>

#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "metro/sim/calibration_session.hpp"
#include "metro/sim/static_session.hpp"
#include "metro/sim/table_session.hpp"
#include "metro/sim/thermal_session.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

// "; truth in FILE" (the default FILE is <output>.truth.json when -o names a file).
std::string TruthNote(const SimulateOptions& o) {
  return o.truth_output.empty() ? "; no truth written (give --truth-output)"
                                : "; truth in " + o.truth_output;
}

// The kinds that write raw-count session.csv of one tag (calibration, thermal): their format
// and tag checked, the truth file named, the outputs checked.
Status CheckOneTagCsv(const char* kind, SimulateOptions* o) {
  if (o->format != "csv") {
    return MakeError(fmt::format("--kind {} writes session.csv (raw LSB columns): drop --format {}",
                                 kind, o->format));
  }
  if (o->sim.sensors.size() != 1) {
    return MakeError(fmt::format("--kind {} simulates one tag: give one --sensor", kind));
  }
  if (o->truth_output.empty() && !IsStdio(o->output)) o->truth_output = o->output + ".truth.json";
  return Status::Ok();
}

int RunCalibrationSimulate(SimulateOptions o) {
  if (Status s = CheckOneTagCsv("calibration", &o); !s.ok()) return PrintErrorExit(s.error());
  SimulationOptions& c = o.calibration;
  c.sensor = o.sim.sensors.front();
  c.seed = o.sim.seed;
  if (o.sim.rate_hz > 0) c.rate_hz = o.sim.rate_hz;
  c.temperature = !o.no_temperature;
  std::string why;
  if (!c.IsValid(&why)) return PrintErrorExit(MakeError(why));
  if (Status s = CheckOutputs({{"-o", o.output}, {"--truth-output", o.truth_output}}, {});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Result<SimulatedSession> sim = SimulateCalibrationSession(c);
  if (!sim.ok()) return PrintErrorExit(sim.error());
  // The session and its truth are replaced together or not at all.
  if (Status s = WriteOutputs({{o.output, FormatSessionCsv(sim.value().session)},
                               {o.truth_output, CalibrationTruthJson(c, sim.value())}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  if (sim.value().saturated_samples > 0) {
    PrintText(stderr,
              fmt::format("warning: {} samples saturated (raw counts at the int16 limits)\n",
                          sim.value().saturated_samples));
  }
  Note(fmt::format("wrote {} (calibration, {} rows, {} poses, seed {}){}\n",
                   IsStdio(o.output) ? "stdout" : o.output, sim.value().session.rows, c.poses,
                   c.seed, TruthNote(o)));
  return kExitOk;
}

int RunThermalSimulate(SimulateOptions o) {
  if (Status s = CheckOneTagCsv("thermal", &o); !s.ok()) return PrintErrorExit(s.error());
  ThermalSimulationOptions& t = o.thermal;
  t.sensor = o.sim.sensors.front();
  t.seed = o.sim.seed;
  if (o.sim.rate_hz > 0) t.rate_hz = o.sim.rate_hz;
  t.profile = o.thermal_profile == "steps"    ? ThermalProfile::kSteps
              : o.thermal_profile == "warmup" ? ThermalProfile::kWarmup
                                              : ThermalProfile::kRamp;
  std::string why;
  if (!t.IsValid(&why)) return PrintErrorExit(MakeError(why));
  if (Status s = CheckOutputs({{"-o", o.output}, {"--truth-output", o.truth_output}}, {});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Result<SimulatedThermalSession> sim = SimulateThermalSession(t);
  if (!sim.ok()) return PrintErrorExit(sim.error());
  // The session and its truth are replaced together or not at all.
  if (Status s = WriteOutputs({{o.output, FormatSessionCsv(sim.value().session)},
                               {o.truth_output, ThermalTruthJson(t, sim.value())}});
      !s.ok()) {
    return PrintErrorExit(s.error());
  }
  Note(fmt::format("wrote {} (thermal, {}, order {}, {} rows, seed {}){}\n",
                   IsStdio(o.output) ? "stdout" : o.output, ThermalProfileName(t.profile),
                   t.bias_order, sim.value().session.rows, t.seed, TruthNote(o)));
  return kExitOk;
}

// --kind table: the table's options from the flags, checked, the truth file named.
Status MakeTableOptions(SimulateOptions* o) {
  Result<TableAxis> axis = ParseTableAxis(o->table_axis);
  if (!axis.ok()) return axis.error();
  o->table.axis = axis.value();
  if (o->sim.sensors.size() != 1) {
    return MakeError("--kind table simulates one tag: give one --sensor");
  }
  o->table.sensor = o->sim.sensors.front();
  o->table.seed = o->sim.seed;
  o->table.rate_hz = o->sim.rate_hz;
  o->table.packet_loss = o->sim.packet_loss;
  o->table.readout_wrap_180 = o->table_readout == "wrap180";
  if (o->truth_output.empty() && !IsStdio(o->output)) o->truth_output = o->output + ".truth.json";
  std::string why;
  if (!o->table.IsValid(&why)) return MakeError(why);
  if (o->format == "receiver" && o->reference_output.empty()) {
    return MakeError("a receiver capture has no table column: give --reference-output");
  }
  return CheckOutputs({{"-o", o->output},
                       {"--reference-output", o->reference_output},
                       {"--truth-output", o->truth_output}},
                      {});
}

// The table session streamed to its file, with its reference log and truth: the three are
// replaced together or not at all.
Status WriteTableSession(const SimulateOptions& o) {
  StreamedOutput writer(o.output);
  std::optional<StreamedOutput> ref_writer, truth_writer;
  if (!o.reference_output.empty()) ref_writer.emplace(o.reference_output);
  if (!o.truth_output.empty()) truth_writer.emplace(o.truth_output);
  Status s = writer.Open();
  if (s.ok() && ref_writer) s = ref_writer->Open();
  if (s.ok() && truth_writer) s = truth_writer->Open();
  TableTruth truth;
  if (s.ok()) {
    TextSink ref_sink = nullptr;
    if (ref_writer) ref_sink = [&](std::string_view chunk) { return ref_writer->Write(chunk); };
    s = SimulateTableSession(
        o.table, o.format == "receiver" ? SessionFormat::kReceiver : SessionFormat::kCsv,
        [&](std::string_view chunk) { return writer.Write(chunk); }, ref_sink, &truth);
  }
  if (s.ok() && truth_writer) s = truth_writer->Write(TableTruthJson(o.table, truth));
  if (s.ok()) s = writer.Finish();
  if (s.ok() && ref_writer) s = ref_writer->Finish();
  if (s.ok() && truth_writer) s = truth_writer->Finish();
  if (s.ok()) s = writer.Publish();
  if (s.ok() && ref_writer) s = ref_writer->Publish();
  if (s.ok() && truth_writer) s = truth_writer->Publish();
  return s;
}

int RunTableSimulate(SimulateOptions o) {
  if (Status s = MakeTableOptions(&o); !s.ok()) return PrintErrorExit(s.error());
  if (Status s = WriteTableSession(o); !s.ok()) return PrintErrorExit(s.error());
  Note(fmt::format("wrote {} (table, {}, seed {}){}\n", IsStdio(o.output) ? "stdout" : o.output,
                   o.format, o.table.seed, TruthNote(o)));
  return kExitOk;
}

// --kind static: tags 1..--tags without the --never ones (or the --sensor list), streamed.
int RunStaticSimulate(SimulateOptions o) {
  if (o.tags > 0) {
    o.sim.sensors.resize(static_cast<size_t>(o.tags));
    std::iota(o.sim.sensors.begin(), o.sim.sensors.end(), 1);
    auto& sensors = o.sim.sensors;
    sensors.erase(std::remove_if(sensors.begin(), sensors.end(),
                                 [&](int s) {
                                   return std::count(o.sim.never_sensors.begin(),
                                                     o.sim.never_sensors.end(), s) > 0;
                                 }),
                  sensors.end());
  }
  o.sim.columns = o.columns == "imu"   ? SimColumns::kImu
                  : o.columns == "all" ? SimColumns::kAll
                                       : SimColumns::kAngles;
  std::string why;
  if (!o.sim.IsValid(&why)) return PrintErrorExit(MakeError(why));
  if (Status s = CheckOutputs({{"-o", o.output}}, {}); !s.ok()) return PrintErrorExit(s.error());
  StreamedOutput writer(o.output);
  const SessionFormat format =
      o.format == "receiver" ? SessionFormat::kReceiver : SessionFormat::kCsv;
  Status s = writer.Open();
  if (s.ok()) {
    s = SimulateStaticSession(o.sim, format,
                              [&](std::string_view chunk) { return writer.Write(chunk); });
  }
  if (s.ok()) s = writer.Commit();
  if (!s.ok()) return PrintErrorExit(s.error());
  Note(fmt::format("wrote {} ({}, seed {})\n", IsStdio(o.output) ? "stdout" : o.output, o.format,
                   o.sim.seed));
  return kExitOk;
}

}  // namespace

int RunSimulate(SimulateOptions o) {
  // An output the chosen kind does not write is a usage error, never silently left unwritten.
  if (o.kind != "table" && !o.reference_output.empty()) {
    return PrintErrorExit(MakeError(
        "--reference-output writes a rotation table's reference log: only with --kind table"));
  }
  if (o.kind == "static" && !o.truth_output.empty()) {
    return PrintErrorExit(MakeError(
        "--truth-output writes the truth of a table, calibration or thermal session (--kind "
        "table, calibration or thermal); a static session's truth is its options "
        "(docs/simulator.md)"));
  }
  if (o.kind == "table") return RunTableSimulate(std::move(o));
  if (o.kind == "calibration") return RunCalibrationSimulate(std::move(o));
  if (o.kind == "thermal") return RunThermalSimulate(std::move(o));
  return RunStaticSimulate(std::move(o));
}

}  // namespace metro::apps
