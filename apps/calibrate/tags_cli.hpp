// The tags file on the calibrate commands (`--tags FILE`, also `--tag-registry FILE`;
// docs/formats.md "Tags file"): which device ID and IMU profile a tag has, for blob and push.
#pragma once

#include <fmt/format.h>

#include <optional>
#include <string>

#include "metro/blob/blob.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/status.hpp"
#include "metro/io/tag_registry.hpp"
#include "tags_names.hpp"

namespace metro::calibrate_app {

// The tags file, or nullopt when none was given.
inline Result<std::optional<TagRegistry>> LoadTagsOption(const std::string& path) {
  if (path.empty()) return std::optional<TagRegistry>();
  Result<TagRegistry> r = TagRegistry::Load(path);
  if (!r.ok()) return r.error();
  return std::optional<TagRegistry>(std::move(r).value());
}

// calibration.json and the tags file (--tags, may be empty), the tags' names and device IDs
// applied to the calibration (apps/tags_names.hpp): a calibration made for another tag (its
// device ID is not the one the file gives the sensor) is refused before anything is read or
// written.
inline Result<Calibration> LoadCalibrationWithTags(const std::string& calibration,
                                                   const std::string& tags_path,
                                                   std::optional<TagRegistry>* tags) {
  Result<Calibration> cal = LoadCalibration(calibration);
  if (!cal.ok()) return cal;
  Result<std::optional<TagRegistry>> loaded = LoadTagsOption(tags_path);
  if (!loaded.ok()) return loaded.error();
  *tags = std::move(loaded).value();
  if (*tags) {
    if (Status s = apps::ApplyTagsToCalibration(**tags, tags_path, &cal.value()); !s.ok()) {
      return s.error();
    }
  }
  return cal;
}

// The device ID a command addresses for `sensor`: --device-id when given, else the tags file's,
// else calibration.json's tag `device_id`; nullopt when none is known. Errors: a --device-id
// that does not parse, and a --device-id or calibration.json ID the tags file gives another tag
// or that disagrees with the file's ID for the sensor; an ID from calibration.json is refused at
// its file:line:column there, naming the tags file's entry at its own, an ID from --device-id at
// the tags file's entry; and a --device-id or tags-file ID other than the device calibration.json
// says the tag was calibrated on, at calibration.json's device_id.
inline Result<std::optional<uint64_t>> ResolveDeviceId(const std::string& flag_text,
                                                       const std::optional<TagRegistry>& tags,
                                                       const Calibration& cal, int sensor) {
  std::optional<uint64_t> id;
  std::string source;
  if (!flag_text.empty()) {
    Result<uint64_t> parsed = blob::ParseDeviceId(flag_text);
    if (!parsed.ok()) return MakeError("--device-id: " + parsed.error().message);
    id = parsed.value();
    source = "--device-id";
  }
  // An error at the tags file's entry (the device_id of sensor `owner`).
  const auto at_entry = [](const TagEntry& entry, std::string message) {
    return MakeError(entry.file, entry.device_id_line, entry.device_id_column, std::move(message));
  };
  const TagEntry* entry = tags ? tags->Find(sensor) : nullptr;
  if (entry != nullptr && entry->device_id) {
    if (id && *id != *entry->device_id) {
      return at_entry(*entry,
                      fmt::format("{} {} is not sensor {}'s device {} in the tags file; expected "
                                  "--device-id {} (or the tags file's entry for that device)",
                                  source, blob::FormatDeviceId(*id), sensor,
                                  blob::FormatDeviceId(*entry->device_id),
                                  blob::FormatDeviceId(*entry->device_id)));
    }
    id = entry->device_id;
    if (source.empty()) source = "the tags file";
  }
  const TagCalibration* t = cal.FindTag(sensor);
  if (!id && t != nullptr && t->device_id) {
    id = t->device_id;
    source = "calibration.json";
  }
  // A calibration made on one device is never written or pushed for another: the constants
  // are that tag's own (as `calibrate apply` refuses it).
  if (id && t != nullptr && t->device_id && *t->device_id != *id) {
    CalibrationPath path = CalibrationTagPath(cal, sensor);
    path.emplace_back(std::string("device_id"));
    const std::string from =
        source == "--device-id" || entry == nullptr ? source : entry->DeviceIdPosition();
    return CalibrationErrorAt(
        cal, path,
        fmt::format("sensor {} was calibrated on device {}, but {} gives device {}: this "
                    "calibration was made for another tag; expected --device-id {} (the "
                    "calibrated tag), or a calibration of device {}",
                    sensor, blob::FormatDeviceId(*t->device_id), from, blob::FormatDeviceId(*id),
                    blob::FormatDeviceId(*t->device_id), blob::FormatDeviceId(*id)));
  }
  if (id && tags) {
    const std::optional<int> owner = tags->SensorOfDevice(*id);
    if (owner && *owner != sensor) {
      const TagEntry& other = *tags->Find(*owner);
      const std::string expected = fmt::format(
          "; expected one device per tag: sensor {}'s own device, or the calibration of sensor "
          "{}",
          sensor, *owner);
      if (source == "calibration.json") {
        CalibrationPath path = CalibrationTagPath(cal, sensor);
        path.emplace_back(std::string("device_id"));
        return CalibrationErrorAt(
            cal, path,
            fmt::format("device {} is sensor {}'s in the tags file ({}), not sensor {}'s{}",
                        blob::FormatDeviceId(*id), *owner, other.DeviceIdPosition(), sensor,
                        expected));
      }
      return at_entry(
          other, fmt::format("{} {} is sensor {}'s in the tags file, not sensor {}'s{}", source,
                             blob::FormatDeviceId(*id), *owner, sensor, expected));
    }
  }
  return id;
}

// --profile when given, else the tags file's for `sensor`, else mpu6050.
inline blob::SensorProfile ResolveProfile(const std::string& flag,
                                          const std::optional<TagRegistry>& tags, int sensor) {
  std::string name = flag;
  const TagEntry* entry = tags ? tags->Find(sensor) : nullptr;
  if (name.empty() && entry != nullptr) name = entry->profile;
  const std::optional<blob::SensorProfile> p = blob::ParseSensorProfile(name);
  return p ? *p : blob::SensorProfile::kMpu6050;  // names were checked by CLI11 and the loader
}

}  // namespace metro::calibrate_app
