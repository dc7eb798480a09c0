#include "metro/io/tag_registry.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "metro/core/file.hpp"
#include "metro/core/json_text.hpp"

namespace metro {

TagRegistry TagRegistry::Default() {
  TagRegistry r;
  r.names_ = {{1, "Forehead"},      {2, "Chest"},       {3, "Left Arm"},    {4, "Right Arm"},
              {5, "Left Wrist"},    {6, "Right Wrist"}, {7, "Left Hand"},   {8, "Right Hand"},
              {9, "Sacral (Back)"}, {10, "Left Knee"},  {11, "Right Knee"}, {12, "Left Ankle"},
              {13, "Right Ankle"},  {14, "Left Foot"},  {15, "Right Foot"}};
  return r;
}

Result<TagRegistry> TagRegistry::Load(const std::string& path) {
  auto text = ReadFile(path);
  if (!text.ok()) return text.error();
  Result<nlohmann::json> parsed = ParseJsonText(text.value(), path);
  if (!parsed.ok()) return parsed.error();
  const nlohmann::json& j = parsed.value();
  if (!j.is_object()) {
    return MakeError(path, 0, R"(expected a JSON object {"1": "Forehead", ...})");
  }
  TagRegistry r = Default();
  for (const auto& [key, value] : j.items()) {
    int sensor = 0;
    try {
      size_t used = 0;
      sensor = std::stoi(key, &used);
      if (used != key.size()) sensor = 0;
    } catch (const std::exception&) {
      sensor = 0;
    }
    if (sensor < 1 || sensor > 255) {
      return MakeError(path, 0, fmt::format("key '{}': expected a tag number 1..255", key));
    }
    if (!value.is_string()) {
      return MakeError(path, 0, fmt::format("tag {}: expected a name string", sensor));
    }
    r.names_[sensor] = value.get<std::string>();
  }
  return r;
}

std::string TagRegistry::Name(int sensor) const {
  const auto it = names_.find(sensor);
  return it != names_.end() ? it->second : fmt::format("tag {}", sensor);
}

}  // namespace metro
