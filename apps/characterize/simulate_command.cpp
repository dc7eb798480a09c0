// characterize simulate -o FILE [--format csv|receiver] [--seed N] [--sensor N]... ...
#include <fmt/format.h>

#include <algorithm>
#include <numeric>

#include "commands.hpp"
#include "metro/core/file.hpp"
#include "metro/sim/static_session.hpp"
#include "output.hpp"

namespace metro::apps {
namespace {

struct SimulateOptions {
  std::string output;
  std::string format = "csv";
  std::string columns = "angles";
  int tags = 0;
  StaticSimulationOptions sim;
};

int RunSimulate(SimulateOptions o) {
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
  if (!o.sim.IsValid(&why)) {
    PrintError(MakeError(why));
    return kExitUsage;
  }
  if (Status s = CheckOutputPath(o.output, {}); !s.ok()) {
    PrintError(s.error());
    return kExitUsage;
  }
  AtomicFileWriter writer(o.output);
  if (Status s = writer.Open(); !s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  const SessionFormat format =
      o.format == "receiver" ? SessionFormat::kReceiver : SessionFormat::kCsv;
  Status s = SimulateStaticSession(o.sim, format,
                                   [&](std::string_view chunk) { return writer.Write(chunk); });
  if (s.ok()) s = writer.Commit();
  if (!s.ok()) {
    PrintError(s.error());
    return kExitFailed;
  }
  fmt::print(stderr, "wrote {} ({}, seed {})\n", o.output, o.format, o.sim.seed);
  return kExitOk;
}

}  // namespace

void AddSimulateCommand(CLI::App& app, int* exit_code) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "write a static tag session with known truth (docs/simulator.md)");
  sub->add_option("-o,--output", o->output, "file to write")->required();
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
  sub->callback([o, exit_code] { *exit_code = RunSimulate(*o); });
}

}  // namespace metro::apps
