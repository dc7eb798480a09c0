#include "conformity_cli.hpp"

#include <fmt/format.h>

#include "commands.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {

LoadedSpec LoadSpecOption(const SpecCliOptions& o) {
  LoadedSpec out;
  if (o.spec.empty()) {
    if (o.fail_on_nonconformity) {
      apps::PrintErrorText("--fail-on-nonconformity needs --spec SPEC.json");
      out.exit_code = kExitUsage;
    }
    return out;
  }
  Result<ConformitySpec> spec = LoadConformitySpec(o.spec);
  if (!spec.ok()) {
    apps::PrintError(spec.error());
    out.exit_code = kExitUsage;
    return out;
  }
  out.spec = std::move(spec).value();
  return out;
}

int ApplySpec(const std::optional<ConformitySpec>& spec, Calibration* calibration) {
  if (!spec) return kExitOk;
  Result<ConformityStatement> st = EvaluateConformity(*calibration, *spec);
  if (!st.ok()) {
    return apps::PrintErrorExit(st.error());
  }
  calibration->conformity = std::move(st).value();
  return kExitOk;
}

int ConformityExitCode(const SpecCliOptions& o, const Calibration& calibration) {
  if (!calibration.conformity) return kExitOk;
  const ConformityStatement& st = *calibration.conformity;
  apps::Note(fmt::format("conformity ({}):\n", DecisionRuleName(st.rule)));
  int fails = 0;
  for (const ConformityEntry& e : st.entries) {
    const std::string line =
        fmt::format("  sensor {} {}: {:.6g} {} (u {:.2g}), p_c {:.4f}: {}\n", e.sensor, e.constant,
                    e.value, e.unit, e.u, e.p_conformance, ConformityDecisionName(e.decision));
    if (e.decision == ConformityDecision::kPass) {
      apps::Note(line);
    } else {
      apps::PrintText(stderr, (apps::Quiet() ? "warning:" : "  warning:") + line.substr(1));
    }
    fails += e.decision == ConformityDecision::kFail ? 1 : 0;
  }
  if (fails > 0 && o.fail_on_nonconformity) {
    apps::PrintErrorText(
        fmt::format("{} constant(s) do not conform to {} (exit 1: "
                    "--fail-on-nonconformity)",
                    fails, o.spec));
    return kExitFailed;
  }
  return kExitOk;
}

}  // namespace metro::calibrate_app
