#include "html_templates.hpp"

#include <fmt/format.h>

#include <ctime>
#include <map>

#include "metro/core/utc_time.hpp"
#include "metro/core/version.hpp"

namespace metro::report_internal {
namespace {

const std::map<std::string, std::string, std::less<>>& Templates() {
  static const std::map<std::string, std::string, std::less<>> templates = {
#include "metro/report/templates_data.inc"
  };
  return templates;
}

}  // namespace

const std::string* FindTemplate(std::string_view name) {
  const auto it = Templates().find(name);
  return it == Templates().end() ? nullptr : &it->second;
}

Result<std::string> RenderTemplate(std::string_view name, kainjow::mustache::data data) {
  const std::string* text = FindTemplate(name);
  if (text == nullptr) return MakeError(fmt::format("no report template '{}'", name));
  for (const auto& [other, other_text] : Templates()) {
    const std::string* captured = &other_text;
    data.set(other + "_view", kainjow::mustache::partial([captured] { return *captured; }));
  }
  try {
    kainjow::mustache::mustache tmpl(*text);
    if (!tmpl.is_valid()) {
      return MakeError(fmt::format("report template '{}': {}", name, tmpl.error_message()));
    }
    std::string out = tmpl.render(data);
    if (!tmpl.is_valid()) {
      return MakeError(fmt::format("report template '{}': {}", name, tmpl.error_message()));
    }
    return out;
  } catch (const std::exception& e) {
    return MakeError(fmt::format("report template '{}': {}", name, e.what()));
  }
}

Result<std::string> RenderPage(const std::string& title, const std::string& subtitle,
                               const std::string& body_html) {
  kainjow::mustache::data data;
  data.set("title", title);
  data.set("subtitle", subtitle);
  data.set("body", body_html);
  data.set("tool", fmt::format("metro {}", kVersion));
  data.set("generated_utc", UtcIso8601Now());
  return RenderTemplate("page", std::move(data));
}

std::string EscapeHtml(std::string_view text) {
  return kainjow::mustache::html_escape<std::string>(std::string(text));
}

}  // namespace metro::report_internal
