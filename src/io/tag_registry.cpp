#include "metro/io/tag_registry.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "core/json_text.hpp"
#include "metro/core/device_id.hpp"
#include "metro/core/file.hpp"

namespace metro {

TagRegistry TagRegistry::Default() {
  TagRegistry r;
  const std::map<int, std::string> names = {
      {1, "Forehead"},      {2, "Chest"},       {3, "Left Arm"},    {4, "Right Arm"},
      {5, "Left Wrist"},    {6, "Right Wrist"}, {7, "Left Hand"},   {8, "Right Hand"},
      {9, "Sacral (Back)"}, {10, "Left Knee"},  {11, "Right Knee"}, {12, "Left Ankle"},
      {13, "Right Ankle"},  {14, "Left Foot"},  {15, "Right Foot"}};
  for (const auto& [sensor, name] : names) r.tags_[sensor] = TagEntry{sensor, name, {}, ""};
  return r;
}

Result<TagRegistry> TagRegistry::Load(const std::string& path) {
  auto text = ReadFile(path);
  if (!text.ok()) return text.error();
  Result<nlohmann::json> parsed = ParseJsonText(text.value(), path);
  if (!parsed.ok()) return parsed.error();
  const nlohmann::json& j = parsed.value();
  constexpr const char* kShape =
      R"(expected a JSON object {"1": "Forehead", "2": {"name": "Chest", "device_id": )"
      R"("12345678 9ABCDEF0", "profile": "mpu6050"}, ...})";
  if (!j.is_object()) return MakeError(path, 0, kShape);
  TagRegistry r = Default();
  std::map<uint64_t, int> devices;
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
    TagEntry e{sensor, "", {}, ""};
    if (value.is_string()) {
      e.name = value.get<std::string>();
    } else if (value.is_object()) {
      for (const auto& [field, v] : value.items()) {
        if (field != "name" && field != "device_id" && field != "profile") {
          return MakeError(path, 0,
                           fmt::format("tag {}: unknown key '{}'; expected name, device_id, "
                                       "profile",
                                       sensor, field));
        }
        if (!v.is_string()) {
          return MakeError(path, 0, fmt::format("tag {}: {}: expected a string", sensor, field));
        }
      }
      if (!value.contains("name")) {
        return MakeError(path, 0, fmt::format("tag {}: expected a name", sensor));
      }
      e.name = value["name"].get<std::string>();
      if (value.contains("device_id")) {
        Result<uint64_t> id = ParseDeviceIdText(value["device_id"].get<std::string>());
        if (!id.ok()) {
          return MakeError(path, 0,
                           fmt::format("tag {}: device_id: {}", sensor, id.error().message));
        }
        if (const auto it = devices.find(id.value()); it != devices.end()) {
          return MakeError(path, 0,
                           fmt::format("tag {}: device_id {} is tag {}'s already", sensor,
                                       FormatDeviceIdText(id.value()), it->second));
        }
        devices[id.value()] = sensor;
        e.device_id = id.value();
      }
      if (value.contains("profile")) {
        e.profile = value["profile"].get<std::string>();
        if (e.profile != "mpu6050" && e.profile != "generic") {
          return MakeError(
              path, 0,
              fmt::format("tag {}: profile '{}': expected mpu6050 or generic", sensor, e.profile));
        }
      }
    } else {
      return MakeError(path, 0,
                       fmt::format("tag {}: expected a name string or an object with name, "
                                   "device_id, profile",
                                   sensor));
    }
    r.tags_[sensor] = std::move(e);
  }
  return r;
}

std::string TagRegistry::Name(int sensor) const {
  const auto it = tags_.find(sensor);
  return it != tags_.end() ? it->second.name : fmt::format("tag {}", sensor);
}

const TagEntry* TagRegistry::Find(int sensor) const {
  const auto it = tags_.find(sensor);
  return it != tags_.end() ? &it->second : nullptr;
}

std::optional<int> TagRegistry::SensorOfDevice(uint64_t device_id) const {
  for (const auto& [sensor, e] : tags_) {
    if (e.device_id == device_id) return sensor;
  }
  return std::nullopt;
}

std::vector<TagEntry> TagRegistry::Entries() const {
  std::vector<TagEntry> out;
  for (const auto& [sensor, e] : tags_) out.push_back(e);
  return out;
}

}  // namespace metro
