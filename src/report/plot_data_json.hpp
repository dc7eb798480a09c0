// The "plot" object of a session report's quantity (docs/report-schema.md): QuantityPlotData
// (metro/report/plot_data.hpp) as JSON and back. The session report's codec embeds it.
// Private to src/report/.
#pragma once

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "metro/report/plot_data.hpp"

namespace metro {

nlohmann::ordered_json PlotDataToJsonValue(const QuantityPlotData& data);

// Reads what PlotDataToJsonValue wrote; a wrong or missing value is recorded in the cursor's
// reading (JsonCursor::ok()).
QuantityPlotData PlotDataFromJsonValue(const JsonCursor& plot);

}  // namespace metro
