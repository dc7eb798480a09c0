// `calibrate fit --spec SPEC.json [--fail-on-nonconformity]`: statements of conformity
// (docs/conformity.md). The hooks fit calls; the work is metro/calibration/conformity.hpp.
#pragma once

#include <optional>
#include <string>

#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/conformity.hpp"

namespace metro::calibrate_app {

struct SpecCliOptions {
  std::string spec;
  bool fail_on_nonconformity = false;
};

// Before the fit: the spec, parsed (an error is printed; exit 2). No --spec: nullopt, ok.
struct LoadedSpec {
  std::optional<ConformitySpec> spec;
  int exit_code = 0;
};
LoadedSpec LoadSpecOption(const SpecCliOptions& options);

// After the fit, before writing: the decisions into calibration->conformity (a constant the
// calibration lacks or a wrong unit: printed, exit 2). 0 when there is no spec.
int ApplySpec(const std::optional<ConformitySpec>& spec, Calibration* calibration);

// After writing: prints the decisions (a failed or inconclusive one always, the rest as notes);
// 1 when any decision is `fail` and --fail-on-nonconformity was given, else 0.
int ConformityExitCode(const SpecCliOptions& options, const Calibration& calibration);

}  // namespace metro::calibrate_app
