// The settle detection of `--settle auto` in a Type A report (docs/report-schema.md):
// options.settle_scope, each sensor's window.settle (method, samples, at_limit as before,
// plus scope and driver: the quantity whose cut the tag window takes) and each quantity's
// own window (window_first_index, t_first_s) and settle object (the fitted transient).
#pragma once

#include "metro/io/session.hpp"
#include "metro/report/session_report.hpp"
#include "metro/stats/session_type_a.hpp"

namespace metro {

// The method named in the report's settle objects.
inline constexpr const char* kSettleMethod =
    "exponential transient fit, cut at remaining bias <= 0.1 u (docs/type-a.md)";

// Adds the keys above to `report`, a MakeSessionReport of `result` (same sensor order).
// Nothing when options.settle_auto is false, apart from options.settle_scope.
void AddSettleToReport(const Session& session, const SessionTypeA& result,
                       const WindowOptions& options, SessionReport* report);

}  // namespace metro
