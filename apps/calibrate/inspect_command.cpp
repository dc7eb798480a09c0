// calibrate inspect tag.bin|tag.hex [--device-id ID] [--tags FILE [--sensor N]] [--slot-address
// ADDR]
//   [--json]
#include "inspect_command.hpp"

#include <fmt/format.h>

#include <memory>

#include "commands.hpp"
#include "metro/blob/inspect.hpp"
#include "tags_cli.hpp"
#include "unix_cli.hpp"

namespace metro::calibrate_app {
namespace {

// The device to check against: --device-id, else the tags file's for --sensor (none: the blob
// is checked without one).
Result<std::optional<uint64_t>> InspectDevice(const InspectCliOptions& c,
                                              const std::optional<TagRegistry>& tags) {
  if (c.sensor != 0 && !tags) {
    return MakeError("--sensor N names a tag of the tags file: give --tags FILE");
  }
  if (c.sensor == 0) {
    if (c.device_id.empty()) return std::optional<uint64_t>();
    Result<uint64_t> id = blob::ParseDeviceId(c.device_id);
    if (!id.ok()) return MakeError("--device-id: " + id.error().message);
    return std::optional<uint64_t>(id.value());
  }
  Result<std::optional<uint64_t>> resolved =
      ResolveDeviceId(c.device_id, tags, Calibration{}, c.sensor);
  if (!resolved.ok()) return MakeError(resolved.error().message).WithKind(resolved.error().kind);
  if (!resolved.value()) {
    return MakeError(
        fmt::format("sensor {} has no device_id in {} (or give --device-id)", c.sensor, c.tags));
  }
  return resolved;
}

// Which tag of the fleet each valid blob is for (a note), or a warning when none. One line
// each: the tag's name and the file's are data (escaped).
void NoteFleetTags(const blob::InspectReport& report, const TagRegistry& tags,
                   const std::string& tags_path) {
  for (const blob::SlotReport& slot : report.slots) {
    if (!slot.contents) continue;
    const uint64_t id = slot.contents->device_id;
    if (const std::optional<int> sensor = tags.SensorOfDevice(id)) {
      apps::Note(fmt::format(
          "slot {}: device {} is sensor {} ({}) in {}\n", slot.label, blob::FormatDeviceId(id),
          *sensor, EscapeControlChars(tags.Name(*sensor)), EscapeControlChars(tags_path)));
    } else {
      apps::PrintText(stderr,
                      fmt::format("warning: slot {}: device {} is no tag's in {}\n", slot.label,
                                  blob::FormatDeviceId(id), EscapeControlChars(tags_path)));
    }
  }
}

}  // namespace

// Exit codes: 0 a valid calibration (the .bin validates; in a .hex a slot is active), 1 none,
// 2 unreadable file, HEX syntax or bad options.
int RunInspect(const InspectCliOptions& c) {
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(c.tags);
  if (!tags.ok()) return apps::PrintErrorExit(tags.error());
  Result<std::optional<uint64_t>> device = InspectDevice(c, tags.value());
  if (!device.ok()) return apps::PrintErrorExit(device.error());
  Result<uint32_t> slot_a = ParseSlotAddress(c.slot_address);
  if (!slot_a.ok()) return apps::PrintErrorExit(slot_a.error());
  blob::InspectOptions o;
  o.device_id = device.value();
  o.slot_a_address = slot_a.value();
  o.slot_b_address = slot_a.value() + blob::kPageSize;
  Result<blob::InspectReport> r = blob::InspectFile(c.input, o);
  if (!r.ok()) return apps::PrintErrorExit(r.error());
  if (c.json) {
    fmt::print("{}\n", blob::ToJson(r.value()));
  } else {
    apps::PrintText(stdout, blob::FormatInspect(r.value()));  // Blob metadata is data.
  }
  if (tags.value()) NoteFleetTags(r.value(), *tags.value(), c.tags);
  return r.value().ok() ? kExitOk : kExitFailed;
}

}  // namespace metro::calibrate_app
