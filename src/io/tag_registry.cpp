#include "metro/io/tag_registry.hpp"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "core/json_reader.hpp"
#include "core/json_text.hpp"
#include "metro/core/device_id.hpp"
#include "metro/core/file.hpp"
#include "metro/core/terminal_text.hpp"

namespace metro {

TagRegistry TagRegistry::Default() {
  TagRegistry r;
  const std::map<int, std::string> names = {
      {1, "Forehead"},      {2, "Chest"},       {3, "Left Arm"},    {4, "Right Arm"},
      {5, "Left Wrist"},    {6, "Right Wrist"}, {7, "Left Hand"},   {8, "Right Hand"},
      {9, "Sacral (Back)"}, {10, "Left Knee"},  {11, "Right Knee"}, {12, "Left Ankle"},
      {13, "Right Ankle"},  {14, "Left Foot"},  {15, "Right Foot"}};
  for (const auto& [sensor, name] : names) {
    TagEntry e;
    e.sensor = sensor;
    e.name = name;
    e.thesis_default = true;
    r.tags_[sensor] = std::move(e);
  }
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
  // Every error at the value it is about: file:line:column, what was expected, the shape.
  const auto at = [&](const std::vector<JsonPathStep>& where, const std::string& message) {
    const auto [line, column] = TextLineColumn(text.value(), JsonValueOffset(text.value(), where));
    return MakeError(path, line, column, message);
  };
  if (!j.is_object()) return at({}, kShape);
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
      return at({key}, fmt::format("key '{}': expected a tag number 1..255 as the key, e.g. "
                                   "\"2\": \"Chest\"",
                                   EscapeControlChars(key)));
    }
    TagEntry e;
    e.sensor = sensor;
    if (value.is_string()) {
      e.name = value.get<std::string>();
    } else if (value.is_object()) {
      for (const auto& [field, v] : value.items()) {
        if (field != "name" && field != "device_id" && field != "profile") {
          return at({key, field},
                    fmt::format("tag {}: unknown key '{}'; expected name, device_id, profile: "
                                "\"{}\": {{\"name\": \"Chest\", \"device_id\": \"12345678 "
                                "9ABCDEF0\", \"profile\": \"mpu6050\"}}",
                                sensor, EscapeControlChars(field), sensor));
        }
        if (!v.is_string()) {
          return at({key, field}, fmt::format("tag {}: {}: expected a string, e.g. \"{}\": {}",
                                              sensor, field, field,
                                              field == "name"        ? "\"Chest\""
                                              : field == "device_id" ? "\"12345678 9ABCDEF0\""
                                                                     : "\"mpu6050\""));
        }
      }
      if (!value.contains("name")) {
        return at({key}, fmt::format("tag {}: expected a name: \"{}\": {{\"name\": \"Chest\", "
                                     "...}}",
                                     sensor, sensor));
      }
      e.name = value["name"].get<std::string>();
      if (value.contains("device_id")) {
        Result<uint64_t> id = ParseDeviceIdText(value["device_id"].get<std::string>());
        if (!id.ok()) {
          return at({key, "device_id"},
                    fmt::format("tag {}: device_id: {}", sensor, id.error().message));
        }
        if (const auto it = devices.find(id.value()); it != devices.end()) {
          return at({key, "device_id"},
                    fmt::format("tag {}: device_id {} is tag {}'s already; expected one device "
                                "per tag",
                                sensor, FormatDeviceIdText(id.value()), it->second));
        }
        devices[id.value()] = sensor;
        e.device_id = id.value();
        const auto [line, column] =
            TextLineColumn(text.value(), JsonValueOffset(text.value(), {key, "device_id"}));
        e.file = path;
        e.device_id_line = line;
        e.device_id_column = column;
      }
      if (value.contains("profile")) {
        e.profile = value["profile"].get<std::string>();
        if (e.profile != "mpu6050" && e.profile != "generic") {
          return at({key, "profile"},
                    fmt::format("tag {}: profile '{}': expected mpu6050 or generic", sensor,
                                EscapeControlChars(e.profile)));
        }
      }
    } else {
      return at({key}, fmt::format("tag {}: expected a name string or an object with name, "
                                   "device_id, profile: \"{}\": \"Chest\" or \"{}\": {{\"name\": "
                                   "\"Chest\", \"device_id\": \"12345678 9ABCDEF0\"}}",
                                   sensor, sensor, sensor));
    }
    r.tags_[sensor] = std::move(e);
  }
  return r;
}

std::string TagEntry::DeviceIdPosition() const {
  if (file.empty()) return "";
  return fmt::format("{}:{}:{}", file, device_id_line, device_id_column);
}

std::string TagRegistry::Name(int sensor) const {
  const auto it = tags_.find(sensor);
  return it != tags_.end() ? it->second.name : fmt::format("tag {}", sensor);
}

bool IsThesisTagFormat(SessionFormat format) {
  switch (format) {
    case SessionFormat::kAuto:
    case SessionFormat::kCsv:
    case SessionFormat::kReceiver:
      return true;
    case SessionFormat::kImuTk:
    case SessionFormat::kEuroc:
    case SessionFormat::kRaw:
    case SessionFormat::kPhyphox:
    case SessionFormat::kSensorLogger:
    case SessionFormat::kPhone:
    case SessionFormat::kULog:
    case SessionFormat::kMcap:
    case SessionFormat::kRosbag1:
    case SessionFormat::kRosbag2:
    case SessionFormat::kDataFlash:
      return false;
  }
  return true;
}

std::string TagRegistry::Name(int sensor, SessionFormat format) const {
  const TagEntry* e = Find(sensor);
  if (IsThesisTagFormat(format) || (e != nullptr && !e->thesis_default)) return Name(sensor);
  return fmt::format("sensor {}", sensor);
}

std::string TagRegistry::Name(int sensor, SessionFormat format,
                              const std::string& source_name) const {
  const TagEntry* e = Find(sensor);
  if (source_name.empty() || (e != nullptr && !e->thesis_default)) return Name(sensor, format);
  return source_name;
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
