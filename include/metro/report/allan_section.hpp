// `characterize SESSION --allan`: the Allan deviation of each tag's rate quantities, in
// the same window as the Type A evaluation, added to the report as
// sensors[i].quantities[name].allan (docs/noise.md) with its link to Type A
// (quantities[name].allan_type_a_link).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "metro/io/session.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/noise_fit.hpp"
#include "metro/noise/sample_period.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

// What --allan does with missing samples (timing gaps: lost packets, absent rows).
enum class AllanGapPolicy {
  kSkip,    // The record on its sample grid; terms that read a missing sample are left out
            // and counted (ComputeAllanWithGaps, NIST SP 1065 5.15, Stable32).
  kSplit,   // Only the longest gap-free stretch is analysed (the other stretches counted).
  kRefuse,  // A gap is an error for that quantity (metro before issue #21).
};
// "skip", "split", "refuse".
const char* AllanGapPolicyName(AllanGapPolicy policy);
Result<AllanGapPolicy> ParseAllanGapPolicy(const std::string& text);

struct SessionAllanOptions {
  AllanOptions allan;
  NoiseFitOptions fit;
  SamplePeriodOptions period;  // allow_gaps is set from `gaps`.
  AllanGapPolicy gaps = AllanGapPolicy::kSkip;
  // A record with more than this fraction of its grid missing is refused whatever `gaps`
  // says (beyond it the estimate rests on a minority of the time span).
  double max_missing_fraction = 0.5;
  // Quantities to analyse; empty: every rate quantity (IsRateQuantity in
  // metro/io/columns.hpp: gyroscope and accelerometer columns, any unit) that the Type A
  // evaluation covered.
  std::vector<std::string> quantities;
};

// What AddAllanToReport did: the quantities it was asked for, how many got a curve, and a
// line for each that did not ("sensor 3 gx_dps: <reason>"), for stderr.
struct AllanSectionSummary {
  int requested = 0;
  int analysed = 0;
  std::vector<std::string> failures;

  // Asked for something and produced nothing at all (the caller exits 1).
  bool NothingProduced() const { return requested > 0 && analysed == 0; }
};

// Adds the "allan" objects to `report` (built by MakeSessionReport from the same `type_a`).
// When `csv` is not null it receives every curve as CSV, one block per tag and quantity
// (nothing when no curve was made).
// A quantity that cannot be analysed (too few samples, a refused gap, a clock that does not
// fit one grid) gets "allan": {"error": "..."} and a line in the summary's failures; the
// others are still analysed. Missing samples are handled by `options.gaps`, and the curve
// says what was missing ("allan.gaps"). Errors: no rate quantity.
Result<AllanSectionSummary> AddAllanToReport(const Session& session, const SessionTypeA& type_a,
                                             const SessionAllanOptions& options,
                                             SessionReport* report, std::string* csv);

// One quantity's sample period and curve (or why not), and the gaps it went through.
struct AllanQuantityCurve {
  Result<SamplePeriod> period = MakeError("not estimated");
  Result<AllanCurve> curve = MakeError("not computed");
  std::optional<AllanGapsReport> gaps;
};
using AllanCurveSource =
    std::function<AllanQuantityCurve(const TagTypeA& tag, const QuantityTypeA& quantity)>;

// AddAllanToReport with the curves from `source` (the streaming mode's spill files); the
// report's blocks are made as AddAllanToReport makes them. `path` names the session.
Result<AllanSectionSummary> AddAllanToReportFrom(const SessionTypeA& type_a,
                                                 const SessionAllanOptions& options,
                                                 const std::string& path,
                                                 const AllanCurveSource& source,
                                                 SessionReport* report, std::string* csv);

// The console summary of a report's Allan sections (empty when there is none): per tag and
// quantity the fitted IEEE 952 N, B and K (IEEE Std 952-1997 Annex C) in the JCGM 100 7.2.2
// concise notation with their units ("-" where the fit found none) and the Allan minimum with
// its tau ("end" when the curve is still falling at its last tau).
std::string AllanSummaryTable(const SessionReport& report);

}  // namespace metro
