// The "spec" member of a session report (characterize SESSION --allan --spec-part PART):
// SpecDecisions as JSON. Private to the library.
#pragma once

#include <nlohmann/json.hpp>

#include "metro/report/spec_decision.hpp"

namespace metro {

nlohmann::ordered_json SpecDecisionsJson(const SpecDecisions& decisions);

}  // namespace metro
