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
//
// The default names are the thesis tags' body parts: they name only the files those tags
// write (a receiver capture, session.csv). Another tool's file (EuRoC, phyphox, Sensor Logger,
// raw-count prints, imu_tk) is some other IMU: Name(sensor, format) gives it "sensor N" unless
// a tags file names that sensor.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct TagEntry {
  int sensor = 0;
  std::string name;
  std::optional<uint64_t> device_id;  // (DEVICEID[1] << 32) | DEVICEID[0]
  std::string profile;                // "mpu6050", "generic", or "" (not given)
  bool thesis_default = false;        // A default name (thesis Table 5.2), not the file's.
  // Where device_id is written: the tags file and the 1-based line and column of its value,
  // for errors that name both it and another file's ID; empty and 0 without a device_id.
  std::string file;
  int64_t device_id_line = 0;
  int64_t device_id_column = 0;

  // "tags.json:3:19", or "" for an entry without a device_id.
  std::string DeviceIdPosition() const;
};

// True for the files the thesis tags write, which the default names belong to: a receiver
// capture and session.csv (kAuto too: a format not yet known). False for other tools' files
// (kEuroc, kPhyphox, kSensorLogger, kRaw, kImuTk).
bool IsThesisTagFormat(SessionFormat format);

class TagRegistry {
 public:
  // Thesis Table 5.2.
  static TagRegistry Default();
  // Default() overlaid with the entries of a JSON object file. Errors name the file and the
  // key, e.g. "tags.json: tag 2: device_id: device id '123': expected ...".
  static Result<TagRegistry> Load(const std::string& path);

  // The tag's name, or "tag N" when the registry has none.
  std::string Name(int sensor) const;
  // The name of `sensor` in a session read as `format`: Name(sensor) for the thesis tags'
  // own files (IsThesisTagFormat); for another tool's file the tags file's name, or
  // "sensor N" where only a default body-part name would apply.
  std::string Name(int sensor, SessionFormat format) const;
  // The same for a tag its input names (Tag::source_name, e.g. a ROS topic): the tags file's
  // name if it has one for `sensor`, else `source_name` when not empty, else the above.
  std::string Name(int sensor, SessionFormat format, const std::string& source_name) const;
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
