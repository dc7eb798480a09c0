// Resolves budget inputs that refer to a session quantity,
//   {"name": "theta", "type_a": {"session": "file.csv", "sensor": 2, "quantity": "pitch_deg"}}
// with metro's Type A evaluation of that session (stats/session_type_a.hpp): the mean, the
// autocorrelation-aware standard uncertainty of the mean (Zhang 2006) and dof = n_eff - 1
// (JCGM 100 G.3: the dof of a Type A evaluation; n_eff replaces n for correlated
// observations). An input without "session" refers to `default_session` (the session
// named on the command line). Loaded sessions are cached.
#pragma once

#include <string>

#include "metro/io/session_io.hpp"
#include "metro/stats/session_type_a.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro {

SessionQuantityResolver MakeSessionQuantityResolver(std::string default_session, LoadOptions load,
                                                    WindowOptions window);

// As above, but inputs of `default_session` are answered from an evaluation already made
// (the command line's --type-a run), so the budget uses exactly the reported numbers and
// windows; quantities that evaluation did not cover are evaluated from `session`.
// `session` and `evaluated` must outlive the resolver.
SessionQuantityResolver MakeSessionQuantityResolver(const Session& session,
                                                    const SessionTypeA& evaluated,
                                                    WindowOptions window);

}  // namespace metro
