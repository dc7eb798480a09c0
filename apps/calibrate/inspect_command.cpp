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
// Exit codes: 0 a valid calibration (the .bin validates; in a .hex a slot is active), 1 none,
// 2 unreadable file, HEX syntax or bad options.
int RunInspect(const InspectCliOptions& c) {
  blob::InspectOptions o;
  Result<std::optional<TagRegistry>> tags = LoadTagsOption(c.tags);
  if (!tags.ok()) {
    return apps::PrintErrorExit(tags.error());
  }
  if (c.sensor != 0 && !tags.value()) {
    apps::PrintErrorText("--sensor N names a tag of the tags file: give --tags FILE");
    return kExitUsage;
  }
  // The device to check against: --device-id, else the tags file's for --sensor.
  Result<std::optional<uint64_t>> resolved =
      c.sensor != 0 ? ResolveDeviceId(c.device_id, tags.value(), Calibration{}, c.sensor)
                    : Result<std::optional<uint64_t>>(std::optional<uint64_t>());
  if (c.sensor == 0 && !c.device_id.empty()) {
    Result<uint64_t> id = blob::ParseDeviceId(c.device_id);
    resolved =
        id.ok() ? Result<std::optional<uint64_t>>(std::optional<uint64_t>(id.value()))
                : Result<std::optional<uint64_t>>(MakeError("--device-id: " + id.error().message));
  }
  if (!resolved.ok()) {
    apps::PrintErrorText(resolved.error().message);
    return apps::ExitCodeFor(resolved.error());
  }
  if (c.sensor != 0 && !resolved.value()) {
    apps::PrintErrorText(
        fmt::format("sensor {} has no device_id in {} (or give --device-id)", c.sensor, c.tags));
    return kExitUsage;
  }
  o.device_id = resolved.value();
  size_t used = 0;
  unsigned long long a = 0;
  try {
    a = std::stoull(c.slot_address, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != c.slot_address.size() || a + 2 * blob::kPageSize > 0x40000) {
    apps::PrintErrorText(
        fmt::format("--slot-address '{}': expected an address below 0x3F800", c.slot_address));
    return kExitUsage;
  }
  o.slot_a_address = static_cast<uint32_t>(a);
  o.slot_b_address = static_cast<uint32_t>(a) + blob::kPageSize;
  Result<blob::InspectReport> r = blob::InspectFile(c.input, o);
  if (!r.ok()) {
    return apps::PrintErrorExit(r.error());
  }
  if (c.json) {
    fmt::print("{}\n", blob::ToJson(r.value()));
  } else {
    apps::PrintText(stdout, blob::FormatInspect(r.value()));  // Blob metadata is data.
  }
  // Which tag of the fleet each valid blob is for (a note), or a warning when none.
  if (tags.value()) {
    for (const blob::SlotReport& slot : r.value().slots) {
      if (!slot.contents) continue;
      const uint64_t id = slot.contents->device_id;
      const std::optional<int> sensor = tags.value()->SensorOfDevice(id);
      if (sensor) {
        // One line each: the tag's name and the file's are data (escaped).
        apps::Note(fmt::format(
            "slot {}: device {} is sensor {} ({}) in {}\n", slot.label, blob::FormatDeviceId(id),
            *sensor, EscapeControlChars(tags.value()->Name(*sensor)), EscapeControlChars(c.tags)));
      } else {
        apps::PrintText(stderr,
                        fmt::format("warning: slot {}: device {} is no tag's in {}\n", slot.label,
                                    blob::FormatDeviceId(id), EscapeControlChars(c.tags)));
      }
    }
  }
  return r.value().ok() ? kExitOk : kExitFailed;
}

}  // namespace metro::calibrate_app
