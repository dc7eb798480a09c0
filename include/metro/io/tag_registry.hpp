// Tag registry, the tags file (`--tags FILE`, or its older name `--tag-registry FILE`): per
// sensor tag, by number, its name and optionally its device ID and IMU profile.
//
// Defaults to thesis Table 5.2 (1 Forehead, 2 Chest, ..., 15 Right foot). A JSON object file
// replaces or extends it; each value is the tag's name, or an object with the name, the tag's
// FICR device ID and its IMU profile (docs/formats.md "Tags file"):
//
//   {"1": "Forehead",
//    "2": {"name": "Chest", "device_id": "12345678 9ABCDEF0", "profile": "mpu6050"}}
//
// device_id takes every spelling of core/device_id.hpp (metro's 16 digits or nrfjprog's two
// words); profile is "mpu6050" or "generic" (`calibrate blob --profile`). Two tags with one
// device ID are refused.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct TagEntry {
  int sensor = 0;
  std::string name;
  std::optional<uint64_t> device_id;  // (DEVICEID[1] << 32) | DEVICEID[0]
  std::string profile;                // "mpu6050", "generic", or "" (not given)
  // Where device_id is written: the tags file and the 1-based line and column of its value,
  // for errors that name both it and another file's ID; empty and 0 without a device_id.
  std::string file;
  int64_t device_id_line = 0;
  int64_t device_id_column = 0;

  // "tags.json:3:19", or "" for an entry without a device_id.
  std::string DeviceIdPosition() const;
};

class TagRegistry {
 public:
  // Thesis Table 5.2.
  static TagRegistry Default();
  // Default() overlaid with the entries of a JSON object file. Errors name the file and the
  // key, e.g. "tags.json: tag 2: device_id: device id '123': expected ...".
  static Result<TagRegistry> Load(const std::string& path);

  // The tag's name, or "tag N" when the registry has none.
  std::string Name(int sensor) const;
  // The tag's entry (the default's or the file's), or nullptr.
  const TagEntry* Find(int sensor) const;
  // The sensor whose device ID this is, if any tag has it.
  std::optional<int> SensorOfDevice(uint64_t device_id) const;
  // Every entry, by sensor number.
  std::vector<TagEntry> Entries() const;

 private:
  std::map<int, TagEntry> tags_;
};

}  // namespace metro
