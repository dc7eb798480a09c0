// The dispatch of a parsed JSON document to its page, for the library and its tests; the
// public entry is RenderJsonFileHtml (metro/report/html_report.hpp), which reads the file.
// Private to src/report/.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "metro/core/status.hpp"
#include "metro/report/html_report.hpp"

namespace metro {

// Any saved JSON document, dispatched on its "schema" key (html_report.hpp). `json_path` is
// where it was read from; a session report is read with SessionReportFromJson from the
// document written out as metro writes it (indent 2), so errors point into such a file. No
// view reloads an input: `session_path` is accepted for the callers of older versions and
// not used.
Result<std::string> RenderJsonHtml(const nlohmann::ordered_json& document,
                                   const std::string& json_path,
                                   const std::string& session_path = "",
                                   const HtmlReportOptions& options = {});

}  // namespace metro
