// calibrate registry history|drift|due|export: queries over the calibration registry
// (docs/registry.md). The work is metro/registry/registry.hpp.
#include "registry_command.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <cmath>
#include <memory>
#include <string>

#include "commands.hpp"
#include "metro/blob/blob.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/registry/registry.hpp"
#include "registry_hooks.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

// A query never creates a registry: a SQLite file must exist.
Result<std::unique_ptr<Registry>> OpenForQuery(const std::string& flag) {
  const std::string url = Registry::UrlFromFlagOrEnvironment(flag);
  if (url.empty()) return MakeError("no registry: give --registry URL or set METRO_REGISTRY");
  struct stat st {};
  if (url.find("://") == std::string::npos && ::stat(url.c_str(), &st) != 0) {
    return MakeError(url, 0, "no such registry file");
  }
  return Registry::OpenForQuery(url);
}

Result<uint64_t> DeviceId(const std::string& text) {
  Result<uint64_t> id = blob::ParseDeviceId(text);
  if (!id.ok()) return MakeError("--device-id: " + id.error().message);
  return id;
}

// Prints `e` and returns its exit code (apps::ExitCodeFor).
int Fail(const Error& e) { return apps::PrintErrorExit(e); }

}  // namespace

int RunRegistryHistory(const RegistryQueryOptions& o) {
  Result<uint64_t> id = DeviceId(o.device_id);
  if (!id.ok()) return Fail(id.error());
  Result<std::unique_ptr<Registry>> r = OpenForQuery(o.url);
  if (!r.ok()) return Fail(r.error());
  Result<std::vector<RegistryCalibration>> h = r.value()->History(id.value());
  if (!h.ok()) return Fail(h.error());
  if (o.json) {
    apps::PrintText(stdout, HistoryToJson(id.value(), h.value()) + "\n");
    return kExitOk;
  }
  std::string out = fmt::format("device {}: {} calibration(s)\n", blob::FormatDeviceId(id.value()),
                                h.value().size());
  // One record per line: every string read from the registry is data (escaped), whoever
  // wrote the file.
  const auto text = [](const std::string& data) { return EscapeControlChars(data); };
  for (const RegistryCalibration& c : h.value()) {
    out += fmt::format("  {} certificate {} sensor {} (registry id {}){}{}\n", text(c.date_utc),
                       text(c.certificate_id), c.sensor, c.id,
                       c.station.empty() ? "" : ", station " + text(c.station),
                       c.operator_name.empty() ? "" : ", operator " + text(c.operator_name));
    for (const RegistryBlob& b : c.blobs) {
      out += fmt::format("    blob seq {} CRC-32 0x{:08X} -> {} ({})\n", b.seq, b.crc, text(b.file),
                         text(b.recorded_utc));
    }
    for (const RegistryPush& p : c.pushes) {
      out += fmt::format("    push {} via {}: {} ({})\n", p.ok ? "OK" : "FAILED", text(p.port),
                         text(p.result), text(p.recorded_utc));
    }
    if (c.conformity) {
      int fails = 0;
      for (const ConformityEntry& e : c.conformity->entries) {
        fails += e.decision == ConformityDecision::kFail ? 1 : 0;
      }
      out += fmt::format("    conformity ({}): {} constant(s), {} fail\n",
                         DecisionRuleName(c.conformity->rule), c.conformity->entries.size(), fails);
    }
  }
  apps::PrintText(stdout, out);
  return kExitOk;
}

int RunRegistryDrift(const RegistryQueryOptions& o) {
  Result<uint64_t> id = DeviceId(o.device_id);
  if (!id.ok()) return Fail(id.error());
  Result<std::unique_ptr<Registry>> r = OpenForQuery(o.url);
  if (!r.ok()) return Fail(r.error());
  Result<DriftResult> d = r.value()->Drift(id.value());
  if (!d.ok()) return Fail(d.error());
  if (d.value().shared_inputs) {
    apps::PrintText(stderr,
                    "warning: the two calibrations share an input record (same SHA-256): their "
                    "covariance is not 0, so u_change is overstated and |E_n| understated\n");
  }
  if (o.json) {
    apps::PrintText(stdout, ToJson(d.value()) + "\n");
    return kExitOk;
  }
  const auto text = [](const std::string& data) { return EscapeControlChars(data); };
  std::string out = fmt::format("device {}: {} ({}) -> {} ({})\n", blob::FormatDeviceId(id.value()),
                                text(d.value().from.date_utc), text(d.value().from.certificate_id),
                                text(d.value().to.date_utc), text(d.value().to.certificate_id));
  out += fmt::format("  {:<12} {:>14} {:>14} {:>12} {:>10} {:>8}  {}\n", "constant", "from", "to",
                     "change", "u_change", "E_n", "unit");
  for (const DriftConstant& k : d.value().constants) {
    out += fmt::format("  {:<12} {:>14.7g} {:>14.7g} {:>12.4g} {:>10.3g} {:>8.3g}  {}{}\n",
                       text(k.name), k.from, k.to, k.change, k.u_change, k.en, text(k.unit),
                       k.flagged ? "  |E_n| > 1" : "");
  }
  apps::PrintText(stdout, out);
  return kExitOk;
}

int RunRegistryDue(const RegistryQueryOptions& o) {
  if (!(o.interval_days > 0) || !std::isfinite(o.interval_days)) {
    apps::PrintErrorText("--interval-days must be a number > 0");
    return kExitUsage;
  }
  const std::string now = o.at_utc.empty() ? UtcIso8601Now() : o.at_utc;
  if (!ParseUtcIso8601(now)) {
    apps::PrintErrorText(
        fmt::format("--at '{}': expected ISO 8601 UTC, e.g. 2026-05-01T12:00:00Z", now));
    return kExitUsage;
  }
  Result<std::unique_ptr<Registry>> r = OpenForQuery(o.url);
  if (!r.ok()) return Fail(r.error());
  Result<std::vector<DueDevice>> due = r.value()->Due(o.interval_days, now, o.all);
  if (!due.ok()) return Fail(due.error().WithKind(ErrorKind::kFailed));
  if (o.json) {
    apps::PrintText(stdout, DueToJson(now, o.interval_days, due.value()) + "\n");
    return kExitOk;
  }
  std::string out = fmt::format("{} device(s) {} at {} (interval {} days)\n", due.value().size(),
                                o.all ? "listed" : "due", now, o.interval_days);
  for (const DueDevice& d : due.value()) {
    out += fmt::format("  {}  last {}  due {}  {}\n", blob::FormatDeviceId(d.device_id),
                       EscapeControlChars(d.last_date_utc), EscapeControlChars(d.due_utc),
                       d.overdue_days > 0 ? fmt::format("overdue {:.1f} days", d.overdue_days)
                                          : fmt::format("in {:.1f} days", -d.overdue_days));
  }
  apps::PrintText(stdout, out);
  return kExitOk;
}

int RunRegistryExport(const RegistryQueryOptions& o) {
  // The registry is the export's input: never written over.
  if (Status s = apps::CheckOutputs({{"-o", o.output}}, RegistryFiles(o.url)); !s.ok()) {
    return Fail(s.error());
  }
  Result<std::unique_ptr<Registry>> r = OpenForQuery(o.url);
  if (!r.ok()) return Fail(r.error());
  Result<std::vector<RegistryCalibration>> all = r.value()->All();
  if (!all.ok()) return Fail(all.error().WithKind(ErrorKind::kFailed));
  std::string text;
  if (o.format == "json") {
    text = ExportToJson(r.value()->schema_version(), all.value()) + "\n";
  } else {
    text = ExportToCsv(all.value());
  }
  if (Status w = apps::WriteOutput(o.output, text); !w.ok()) return Fail(w.error());
  return kExitOk;
}

}  // namespace metro::calibrate_app
