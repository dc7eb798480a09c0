// The dispatch of a parsed JSON document to its page, for the library and its tests; the
// public entry is RenderJsonFileHtml (metro/report/html_report.hpp), which reads the file.
// Private to src/report/.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "metro/core/status.hpp"
#include "metro/report/html_report.hpp"

namespace metro {

// The text of any saved JSON document, dispatched on its "schema" key (html_report.hpp): each
// typed document read with its FromJson from `text`, so errors name the value's line and column
// in the file `json_path` with its path. RenderJsonFileHtml reads the file and calls this.
Result<std::string> RenderJsonTextHtml(std::string_view text, const std::string& json_path,
                                       const HtmlReportOptions& options = {});

// A parsed document (tests), written out as metro writes it (indent 2) and rendered with
// RenderJsonTextHtml.
Result<std::string> RenderJsonHtml(const nlohmann::ordered_json& document,
                                   const std::string& json_path,
                                   const HtmlReportOptions& options = {});

}  // namespace metro
