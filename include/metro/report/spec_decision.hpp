// A measurement's IEEE 952 noise terms judged against a part's datasheet figures
// (`characterize SESSION --allan --spec-part PART`, issue #40 step 5; docs/specs.md).
//
// Per axis and term (N, B, K), the measurement X with standard uncertainty u(X) is expressed in
// the figure's convention and unit (spec_library.hpp): a one-sided density as sqrt(2) N, an
// ARW/VRW as N, an "in-run bias stability" as the minimum of the Allan deviation curve (u from
// its confidence interval), a bias random walk as K. Then, by the figure's kind:
//
//   max / min   a specification limit: the JCGM 106:2012 decision of calibration/conformity.hpp
//               (DecideConformity: p_c, and the rule, guarded by default: pass if
//               X <= T_U - k u, fail if X > T_U, otherwise inconclusive);
//   typ / unstated
//               not a limit (a typical part, no tolerance): no pass or fail, only
//               ratio = X / x and E_n = (X - x) / sqrt(U_X^2 + U_x^2), U_X = 2 u(X), U_x = 0
//               (ISO 13528:2015 9.7), as noise-compare reports;
//   config      never used: a value someone chose for an estimator, not the part's.
//
// A term the datasheet gives no figure for is a row saying so (K is rarely given: a bias
// instability is not a random walk); a term the record did not resolve is a row with the
// reason. Nothing is filled in.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "metro/calibration/conformity.hpp"
#include "metro/core/status.hpp"
#include "metro/noise/noise_export.hpp"
#include "metro/noise/spec_library.hpp"

namespace metro {

struct SpecDecisionRow {
  std::string quantity;  // "gx_dps"; empty for a row about the datasheet (no figure).
  SensorKind sensor = SensorKind::kNone;
  NoiseTerm term = NoiseTerm::kRandomWalk;
  std::optional<SpecFigure> figure;           // nullopt: the datasheet gives none.
  std::string document;                       // "PS-MPU-6000A-00 rev. 3.4 page 12".
  double measured = std::nan("");             // In the figure's unit and convention.
  double u = std::nan("");                    // k = 1.
  double ratio = std::nan("");                // measured / figure.
  double e_n = std::nan("");                  // (measured - figure) / (2 u).
  std::optional<ConformityEntry> conformity;  // max/min figures only.
  std::string note;
};

struct SpecDecisions {
  std::string part;
  std::string library;
  DecisionRule rule = DecisionRule::kGuarded;
  double coverage_factor = 2.0;
  double max_consumer_risk = 0.0;
  std::vector<SpecDecisionRow> rows;
};

struct SpecDecisionOptions {
  DecisionRule rule = DecisionRule::kGuarded;
  double coverage_factor = 2.0;
  double max_consumer_risk = 0.023;  // Used by the risk rule only.
};

// Judges every accelerometer and gyroscope axis of `input` (a report's tag with --allan)
// against the datasheet figures of `part` (kinds typ, unstated, min, max; the first figure of a
// sensor and term counts). Errors (input): no accelerometer or gyroscope axis, no datasheet
// document in the part (only published configs), a quantity unit without an SI scale.
Result<SpecDecisions> DecideAgainstSpec(const NoiseExportInput& input, const SpecPart& part,
                                        const std::string& library_file,
                                        const SpecDecisionOptions& options);

// "N", "B" or "K".
const char* SpecTermSymbol(NoiseTerm term);

// How the figures are judged: the conventions, the rule for max/min figures, typ figures'
// ratio and E_n (three lines, the end of SpecDecisionsTable and the page's note).
std::string SpecRulesText(const SpecDecisions& decisions);

// The plain-text table: quantity, term, figure (kind, convention), measured, u, ratio, E_n,
// decision or note; then how typ and max figures are judged.
std::string SpecDecisionsTable(const SpecDecisions& decisions);

}  // namespace metro
