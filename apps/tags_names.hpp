// The tags file (`--tags FILE`, also `--tag-registry FILE`; docs/formats.md "Tags file") on
// the commands that name tags after the fact: `calibrate apply` and `calibrate report`,
// `characterize report` and `characterize capture`. As everywhere, the file overlays the
// default names (thesis Table 5.2): TagRegistry::Find gives an entry for every sensor 1..15.
#pragma once

#include <fmt/format.h>

#include <optional>
#include <string>
#include <vector>

#include "metro/blob/blob.hpp"
#include "metro/calibration/calibrate.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/core/status.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/io/tag_registry.hpp"
#include "metro/report/certificate.hpp"

namespace metro::apps {

// Gives each tag of `cal` the tags file's name, its profile when the file names one, and its
// device ID where calibration.json records none. A calibration fitted only from other tools'
// files is not a thesis tag's: a default body-part name does not apply to it, and its tags keep
// the name calibration.json gives them (CalibrationRecordsFormat). Input
// errors (exit 2) at the file:line:column of calibration.json's device_id, naming the tags file's
// entry at its own (or `tags_path`): calibration.json's device ID for a sensor differs from the
// file's for that sensor, or the file gives that device to another sensor (the calibration belongs
// to another tag).
inline Status ApplyTagsToCalibration(const TagRegistry& tags, const std::string& tags_path,
                                     Calibration* cal) {
  const SessionFormat records = CalibrationRecordsFormat(*cal);
  for (TagCalibration& t : cal->tags) {
    const TagEntry* entry = tags.Find(t.sensor);
    if (t.device_id) {
      CalibrationPath at = CalibrationTagPath(*cal, t.sensor);
      at.emplace_back(std::string("device_id"));
      // The tags file's entry by its position when it has one.
      const auto where = [&tags_path](const TagEntry& e) {
        return e.file.empty() ? tags_path : e.DeviceIdPosition();
      };
      if (entry != nullptr && entry->device_id && *entry->device_id != *t.device_id) {
        return CalibrationErrorAt(
            *cal, at,
            fmt::format("sensor {} is device {} in calibration.json but device {} in {}: this "
                        "calibration was made for another tag; expected the calibration of "
                        "device {} (or a tags file that gives sensor {} device {})",
                        t.sensor, blob::FormatDeviceId(*t.device_id),
                        blob::FormatDeviceId(*entry->device_id), where(*entry),
                        blob::FormatDeviceId(*entry->device_id), t.sensor,
                        blob::FormatDeviceId(*t.device_id)));
      }
      const std::optional<int> owner = tags.SensorOfDevice(*t.device_id);
      if (owner && *owner != t.sensor) {
        return CalibrationErrorAt(
            *cal, at,
            fmt::format("sensor {} of calibration.json is device {}, which {} gives sensor {}: "
                        "this calibration was made for another tag; expected one device per "
                        "tag: the calibration of sensor {}'s own device",
                        t.sensor, blob::FormatDeviceId(*t.device_id), where(*tags.Find(*owner)),
                        *owner, t.sensor));
      }
    }
    if (entry == nullptr) continue;
    if (IsThesisTagFormat(records) || !entry->thesis_default) t.name = entry->name;
    if (!entry->profile.empty()) t.profile = entry->profile;
    if (!t.device_id) t.device_id = entry->device_id;
  }
  return Status::Ok();
}

// One line per tag of `cal`: "  sensor 2: Chest, device 9ABCDEF012345678, profile mpu6050"
// (the parts that are known).
inline std::string CalibrationTagLines(const Calibration& cal) {
  std::string out;
  for (const TagCalibration& t : cal.tags) {
    // One line per tag: the name is the tags file's data (escaped).
    out += fmt::format("  sensor {}: {}", t.sensor,
                       t.name.empty() ? "(no name)" : EscapeControlChars(t.name));
    if (t.device_id) out += ", device " + blob::FormatDeviceId(*t.device_id);
    if (!t.profile.empty()) out += ", profile " + EscapeControlChars(t.profile);
    out += "\n";
  }
  return out;
}

// The certificate of calibration.json at `path`, rendered for `cal` (the file's calibration
// with the tags file applied) as RenderJsonFileHtml renders the file itself: the certificate id
// the hash of the file's own bytes (what `fit` printed and the registry recorded).
inline Result<std::string> RenderCertificateFor(const Calibration& cal, const std::string& path,
                                                bool accept_rejected_model = false,
                                                bool view = false) {
  CertificateOptions certificate;
  certificate.accept_rejected_model = accept_rejected_model;
  certificate.view = view;
  Result<std::string> sha = Sha256File(path);
  if (sha.ok()) certificate.certificate_id = sha.value().substr(0, 16);
  return RenderCalibrationCertificate(cal, certificate);
}

}  // namespace metro::apps
