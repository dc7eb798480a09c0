// The mustache templates of reports/templates/, compiled into the library, and rendering
// with kainjow::mustache (HTML-escaping {{name}}, raw {{{name}}}).
#pragma once

#include <kainjow/mustache.hpp>
#include <string>
#include <string_view>

#include "metro/core/status.hpp"

namespace metro::report_internal {

// The template text of reports/templates/<name>.mustache, or nullptr.
const std::string* FindTemplate(std::string_view name);

// Renders template `name` with `data`; every other template is available as a partial
// {{>name_view}} (e.g. {{>budget_view}} for budget.mustache). Errors: unknown template, a
// template syntax error.
Result<std::string> RenderTemplate(std::string_view name, kainjow::mustache::data data);

// Wraps a body in page.mustache: title, subtitle, tool and generation time.
Result<std::string> RenderPage(const std::string& title, const std::string& subtitle,
                               const std::string& body_html);

// HTML-escapes text for direct insertion.
std::string EscapeHtml(std::string_view text);

}  // namespace metro::report_internal
