// `characterize SESSION --allan`: the Allan deviation of each tag's rate quantities, in
// the same window as the Type A evaluation, added to the report as
// sensors[i].quantities[name].allan (docs/noise.md) with its link to Type A
// (quantities[name].allan_type_a_link).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "metro/io/session.hpp"
#include "metro/noise/allan.hpp"
#include "metro/noise/noise_fit.hpp"
#include "metro/noise/sample_period.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

struct SessionAllanOptions {
  AllanOptions allan;
  NoiseFitOptions fit;
  SamplePeriodOptions period;
  // Quantities to analyse; empty: every rate quantity (IsRateQuantity in
  // metro/io/columns.hpp: gyroscope and accelerometer columns, any unit) that the Type A
  // evaluation covered.
  std::vector<std::string> quantities;
};

// Adds the "allan" objects to `report` (built by TypeAReportJson from the same `type_a`).
// When `csv` is not null it receives every curve as CSV, one block per tag and quantity.
// A quantity that cannot be analysed (timing gaps, too few samples) gets
// "allan": {"error": "..."}; the others are still analysed. Errors: no rate quantity.
Status AddAllanToReport(const Session& session, const SessionTypeA& type_a,
                        const SessionAllanOptions& options, nlohmann::ordered_json* report,
                        std::string* csv);

}  // namespace metro
