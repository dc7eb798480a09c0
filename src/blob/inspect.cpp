#include "metro/blob/inspect.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <nlohmann/json.hpp>
#include <tuple>

#include "core/json_text.hpp"
#include "metro/blob/intel_hex.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/utc_time.hpp"
#include "metro_fw/blob.h"

namespace metro::blob {
namespace {

// METRO_FW_E_SENSOR: the validator refused the blob's sensors after its section walk passed,
// so info locates the sections and the gate below can say which sensor and why.
constexpr int kFwSensorRefused = METRO_FW_E_SENSOR;

bool SectionsLocated(int code) { return code == METRO_FW_OK || code == kFwSensorRefused; }

const char* StatusReason(int status) {
  switch (status) {
    case METRO_FW_SENSOR_UNSUPPORTED:
      return "a section major this firmware does not know";
    case METRO_FW_SENSOR_NONFINITE:
      return "a NaN or Inf constant, or a negative uncertainty; expected finite constants";
    case METRO_FW_SENSOR_BAD_MODEL:
      return "model bits outside 0x01, 0x02, 0x04, 0x08, 0x80, or (section v2.0) an input "
             "encoding other than 0 (int16) and 1 (offset binary)";
    case METRO_FW_SENSOR_CONFIG_MISMATCH:
      return "fs_sel above 3 or dlpf_cfg above 6, a configuration no tag has";
    case METRO_FW_SENSOR_LIMITS:
      return "expected row norms of M within 10 % of the nominal sensitivity, det(M) > 0, bias "
             "within 0.25 g / 60 deg/s, temperature coefficient |b1| + 2 |b2| D within 4.9 "
             "mg/degC / 0.67 deg/s/degC and -40 <= t_valid_min_c, t_valid_min_c + 2 <= "
             "t_valid_max_c <= 85 (section 3.1; for a section v2.0 relative to its declared "
             "s_nom, 2^-14 .. 2^-7 SI per LSB, with fs_sel 0's bias and temperature-coefficient "
             "limits in counts about the input's zero)";
    default:
      return "see docs/calibration-blob.md section 3.1";
  }
}

// "bytes 0x0B0-0x15F" in a .bin, "0x3B0B0-0x3B15F" in a slot of a .hex.
std::string Range(uint32_t base, uint64_t begin, uint64_t end) {
  if (base == 0) return fmt::format("bytes 0x{:03X}-0x{:03X}", begin, end - 1);
  return fmt::format("0x{:05X}-0x{:05X}", base + begin, base + end - 1);
}

// The gate's sensor rules (docs/calibration-blob.md section 8.1) on a blob whose sections the
// validator located: flags b0/b1 name exactly the sections present, at least one is present,
// each is usable on a tag configured as the section says, flag b2 matches the temperature terms.
void SensorGate(const std::vector<uint8_t>& bytes, const metro_fw_blob_info& info,
                const std::string& where, uint32_t base, const uint32_t id[2], SlotReport* r,
                std::vector<std::string>* refusals) {
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  bool temp_terms = false;
  for (const auto& [name, kind, off, bit, version] :
       {std::tuple{"accel", METRO_FW_ACCEL, info.accel_off, 0, info.accel_version},
        std::tuple{"gyro", METRO_FW_GYRO, info.gyro_off, 1, info.gyro_version}}) {
    const bool declared = ((info.flags >> bit) & 1u) != 0;
    const std::string range = Range(base, off, off + uint64_t{METRO_FW_SENSOR_BODY_LEN});
    if (declared && off == 0) {
      refusals->push_back(fmt::format(
          "{}: flags 0x{:08X} declare a {} section (bit b{}) that the blob does not hold; the tag "
          "would run the {} on default constants; expected flags naming exactly the sensor "
          "sections present",
          where, info.flags, name, bit, name));
    } else if (!declared && off != 0) {
      refusals->push_back(fmt::format(
          "{}: the {} section at {} is not declared by flags 0x{:08X} (bit b{} clear); expected "
          "flags naming exactly the sensor sections present",
          where, name, range, info.flags, bit));
    }
    metro_fw_config cfg{};
    cfg.device_id[0] = id[0];
    cfg.device_id[1] = id[1];
    if (off != 0 && off + 2u <= bytes.size()) {
      const uint8_t fs = std::min<uint8_t>(bytes[off], 3);
      cfg.accel_fs_sel = fs;
      cfg.gyro_fs_sel = fs;
      cfg.dlpf_cfg = bytes[off + 1];
      // section v2.0: a tag whose driver delivers the input the section declares
      if ((version >> 8) == 2 && off + 4u <= bytes.size()) {
        cfg.accel_input = bytes[off + 3];
        cfg.gyro_input = bytes[off + 3];
      }
    }
    metro_fw_sensor_cal cal{};
    METRO_CHECK(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, &cfg, &cal) ==
                METRO_FW_OK);
    // An fs_sel above 3 is a configuration no tag has: report it as a mismatch.
    int status = cal.status;
    if (off != 0 && bytes[off] > 3) status = METRO_FW_SENSOR_CONFIG_MISMATCH;
    r->sensors.push_back(SensorVerdict{name, status, SensorStatusName(status)});
    if (off != 0 && status != METRO_FW_SENSOR_OK) {
      refusals->push_back(fmt::format(
          "{}: the {} section at {} is {}: {}; the tag would run the {} on default constants",
          where, name, range, SensorStatusName(status), StatusReason(status), name));
    }
    if (off != 0 && status == METRO_FW_SENSOR_OK) {
      temp_terms |= (cal.model_bits & (kModelLinearT | kModelQuadraticT)) != 0;
    }
  }
  if (info.accel_off == 0 && info.gyro_off == 0) {
    refusals->push_back(fmt::format(
        "{}: no accel and no gyro section: the tag would run both sensors on default constants; "
        "expected at least one sensor section",
        where));
  }
  const bool temp_flag = (info.flags & METRO_FW_FLAG_TEMP_MODEL) != 0;
  const bool all_ok = std::all_of(r->sensors.begin(), r->sensors.end(), [](const auto& v) {
    return v.status == METRO_FW_SENSOR_OK || v.status == METRO_FW_SENSOR_ABSENT;
  });
  if (all_ok && temp_flag != temp_terms) {
    refusals->push_back(fmt::format(
        "{}: flags 0x{:08X} {} the temperature model (bit b2) but the sensor sections have {} "
        "temperature term (model bits 0x04, 0x08)",
        where, info.flags, temp_flag ? "declare" : "do not declare", temp_terms ? "a" : "no"));
  }
}

// The slot as the firmware sees it: validator, then each sensor on a tag configured as the
// section itself says (fs_sel, dlpf_cfg), so only physical limits and finiteness can fail;
// the gate's refusals go to `refusals`. `base` is the slot's address (0 for a .bin).
SlotReport InspectSlot(const std::vector<uint8_t>& bytes, const std::string& label,
                       uint32_t address, const InspectOptions& options,
                       std::vector<std::string>* refusals, metro_fw_blob_info* info_out) {
  SlotReport r;
  r.label = label;
  r.address = address;
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  uint32_t id[2] = {0, 0};
  if (options.device_id) {
    id[0] = static_cast<uint32_t>(*options.device_id & 0xFFFFFFFFu);
    id[1] = static_cast<uint32_t>(*options.device_id >> 32);
  } else if (bytes.size() >= 24) {
    for (int i = 0; i < 4; ++i) {
      id[0] |= uint32_t{bytes[16 + i]} << (8 * i);
      id[1] |= uint32_t{bytes[20 + i]} << (8 * i);
    }
  }
  metro_fw_blob_info info{};
  r.code = metro_fw_blob_validate(metro_fw_buffer_read, &buf, buf.len, id, &info);
  r.code_name = FirmwareErrorName(r.code);
  r.message = FirmwareErrorMessage(r.code);
  if (info_out != nullptr) *info_out = info;
  if (!SectionsLocated(r.code)) return r;
  const std::string where = address ? fmt::format("slot {}", label) : "blob";
  SensorGate(bytes, info, where, address, id, &r, refusals);
  if (r.code != METRO_FW_OK) return r;
  auto decoded = DecodeBlob(bytes, uint64_t{id[1]} << 32 | id[0]);
  METRO_CHECK(decoded.ok());  // the same validator accepted it a moment ago
  r.contents = std::move(decoded).value();
  return r;
}

// The nRF51802's memory map (docs/calibration-blob.md section 1), to name what a write
// outside the calibration slots would overwrite.
struct Region {
  uint64_t begin, end;
  const char* name;
};
constexpr Region kRegions[] = {
    {0x00000, 0x18000, "the MBR and SoftDevice S110 (0x00000-0x17FFF)"},
    {0x18000, 0x3B000, "the application (0x18000-0x3AFFF)"},
    {0x3B000, 0x3B800, "the default calibration slots (0x3B000-0x3B7FF), not the ones inspected"},
    {0x3B800, 0x3C000, "the pages between slot B and the bootloader (0x3B800-0x3BFFF)"},
    {0x3C000, 0x40000, "the DFU bootloader (0x3C000-0x3FFFF)"},
    {0x40000, 0x10000000, "no flash (the nRF51802 has 256 KiB, 0x00000-0x3FFFF)"},
    {0x10000000, 0x10001000, "the FICR (factory information, read-only)"},
    {0x10001000, 0x10002000, "the UICR (bootloader address, readback protection)"},
    {0x10002000, 0x100000000, "no flash"},
};

// The byte ranges of `segments` outside both slot pages, split at region boundaries.
void OutsideSlots(const std::vector<HexSegment>& segments, const InspectOptions& o,
                  std::vector<std::string>* refusals) {
  const uint64_t slots[2][2] = {{o.slot_a_address, uint64_t{o.slot_a_address} + kPageSize},
                                {o.slot_b_address, uint64_t{o.slot_b_address} + kPageSize}};
  constexpr size_t kMaxListed = 16;
  size_t found = 0;
  for (const HexSegment& seg : segments) {
    std::vector<std::pair<uint64_t, uint64_t>> parts = {
        {seg.address, uint64_t{seg.address} + seg.bytes.size()}};
    for (const auto& slot : slots) {
      std::vector<std::pair<uint64_t, uint64_t>> rest;
      for (const auto& [b, e] : parts) {
        if (e <= slot[0] || b >= slot[1]) {
          rest.push_back({b, e});
          continue;
        }
        if (b < slot[0]) rest.push_back({b, slot[0]});
        if (e > slot[1]) rest.push_back({slot[1], e});
      }
      parts = rest;
    }
    for (const auto& [b, e] : parts) {
      for (const Region& region : kRegions) {
        const uint64_t lo = std::max(b, region.begin), hi = std::min(e, region.end);
        if (lo >= hi) continue;
        if (++found > kMaxListed) continue;
        refusals->push_back(fmt::format(
            "0x{:08X}-0x{:08X} ({} bytes) is written in {}: a calibration image writes only "
            "slot A 0x{:05X}-0x{:05X} and slot B 0x{:05X}-0x{:05X}",
            lo, hi - 1, hi - lo, region.name, slots[0][0], slots[0][1] - 1, slots[1][0],
            slots[1][1] - 1));
      }
    }
  }
  if (found > kMaxListed) {
    refusals->push_back(
        fmt::format("... and {} more ranges outside the calibration slots", found - kMaxListed));
  }
}

// Reads at most kMaxInspectFileBytes: the size is checked before anything is read, and a file
// that grows meanwhile is still cut off at the limit.
Result<std::string> ReadBounded(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return MakeError(path, 0, fmt::format("cannot open: {}", std::strerror(errno)));
  struct stat st {};
  std::string out;
  const auto too_large = [&](uint64_t size) {
    return MakeError(path, 0,
                     fmt::format("{}{} bytes; calibrate inspect reads at most {} bytes (both slot "
                                 "pages as Intel HEX take about 6 KiB, a .bin at most 1024 bytes)",
                                 size > kMaxInspectFileBytes + 1 ? "" : "more than ", size,
                                 kMaxInspectFileBytes));
  };
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return MakeError(path, 0, "not a regular file; expected a tag.bin or tag.hex file");
  }
  if (static_cast<uint64_t>(st.st_size) > kMaxInspectFileBytes) {
    ::close(fd);
    return too_large(static_cast<uint64_t>(st.st_size));
  }
  out.resize(kMaxInspectFileBytes + 1);
  size_t n = 0;
  while (n < out.size()) {
    const ssize_t got = ::read(fd, out.data() + n, out.size() - n);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      const int err = errno;
      ::close(fd);
      return MakeError(path, 0, fmt::format("cannot read: {}", std::strerror(err)));
    }
    if (got == 0) break;
    n += static_cast<size_t>(got);
  }
  ::close(fd);
  if (n > kMaxInspectFileBytes) return too_large(n);
  out.resize(n);
  return out;
}

std::string Hex(const uint8_t* p, size_t n) {
  std::string s;
  for (size_t i = 0; i < n; ++i) s += fmt::format("{:02x}", p[i]);
  return s;
}

// A binary32 field as its shortest round-trip decimal (the blob stores binary32, so this is
// exactly what the tag holds).
std::string F32(double v) { return fmt::format("{}", static_cast<float>(v)); }

template <size_t N>
std::string F32s(const std::array<double, N>& v) {
  std::string out = "[";
  for (size_t i = 0; i < N; ++i) out += (i ? " " : "") + F32(v[i]);
  return out + "]";
}

// Seconds since 1970-01-01 UTC as ISO 8601, e.g. 2026-05-28T20:26:40Z.
std::string IsoDateUtc(uint32_t t_s) {
  const std::string text = UtcIso8601(static_cast<std::time_t>(t_s));
  return text.empty() ? fmt::format("{} s", t_s) : text;
}

// The whole sensor section, as the tag holds it (docs/calibration-blob.md 2.4 and 3).
std::string SensorText(const SensorConstants& s, bool accel) {
  const char* si = accel ? "m/s^2" : "rad/s";
  std::string out = fmt::format("    M [{} per LSB], row-major, and u(M) (k = 1):\n", si);
  for (size_t r = 0; r < 3; ++r) {
    out += fmt::format("      [{:>15} {:>15} {:>15}]  u [{} {} {}]\n", F32(s.m[3 * r]),
                       F32(s.m[3 * r + 1]), F32(s.m[3 * r + 2]), F32(s.u_m[3 * r]),
                       F32(s.u_m[3 * r + 1]), F32(s.u_m[3 * r + 2]));
  }
  const auto used = [&](uint8_t bit) {
    return (s.model_bits & bit) ? "" : " (bit clear: not applied)";
  };
  if (s.s_nom_si_per_lsb) {
    // section v2.0 (issue #25): the declared nominal and the raw input
    const double unit = accel ? 9.80665 : 3.14159265358979323846 / 180.0;
    out += fmt::format(
        "    section v2.0: s_nom {} {} per LSB ({:.6g} {}); input {}\n", F32(*s.s_nom_si_per_lsb),
        si, unit / *s.s_nom_si_per_lsb, accel ? "LSB/g" : "LSB/(deg/s)",
        s.input == kInputOffsetBinary
            ? "offset binary (unsigned 16-bit counts; b0 relative to the mid-scale 32768)"
        : s.input == kInputInt16 ? "int16 (signed counts)"
                                 : fmt::format("code {} (unknown)", s.input));
  }
  out += fmt::format("    b0 {} LSB, u {}{}\n", F32s(s.b0_lsb), F32s(s.u_b0_lsb), used(kModelBias));
  out += fmt::format("    b1 {} LSB/degC, u {}{}\n", F32s(s.b1_lsb_per_c), F32s(s.u_b1_lsb_per_c),
                     used(kModelLinearT));
  out += fmt::format("    b2 {} LSB/degC^2, u {}{}\n", F32s(s.b2_lsb_per_c2),
                     F32s(s.u_b2_lsb_per_c2), used(kModelQuadraticT));
  out += fmt::format(
      "    t_ref {} degC; validity range {} .. {} degC (the tag clamps the temperature to it)\n",
      F32(s.t_ref_c), F32(s.t_valid_min_c), F32(s.t_valid_max_c));
  out += fmt::format("    resid_rms {} {}; hw_offs [{} {} {}]{}\n", F32(s.resid_rms_si), si,
                     s.hw_offs[0], s.hw_offs[1], s.hw_offs[2],
                     (s.model_bits & kModelHwOffsets) ? " (written to the MPU6050)"
                                                      : " (bit 0x80 clear: not written)");
  return out;
}

nlohmann::json SensorJson(const SensorConstants& s) {
  nlohmann::json j;
  j["section_version"] = s.s_nom_si_per_lsb ? "2.0" : "1.0";
  if (s.s_nom_si_per_lsb) {
    j["s_nom_si_per_lsb"] = *s.s_nom_si_per_lsb;
    j["input"] = s.input == kInputOffsetBinary ? "offset_binary"
                 : s.input == kInputInt16      ? "int16"
                                               : std::to_string(s.input);
  }
  j["fs_sel"] = s.fs_sel;
  j["dlpf_cfg"] = s.dlpf_cfg;
  j["model_bits"] = s.model_bits;
  j["t_ref_c"] = s.t_ref_c;
  j["m_si_per_lsb"] = s.m;
  j["b0_lsb"] = s.b0_lsb;
  j["b1_lsb_per_c"] = s.b1_lsb_per_c;
  j["b2_lsb_per_c2"] = s.b2_lsb_per_c2;
  j["u_m_si_per_lsb"] = s.u_m;
  j["u_b0_lsb"] = s.u_b0_lsb;
  j["u_b1_lsb_per_c"] = s.u_b1_lsb_per_c;
  j["u_b2_lsb_per_c2"] = s.u_b2_lsb_per_c2;
  j["resid_rms_si"] = s.resid_rms_si;
  j["t_valid_min_c"] = s.t_valid_min_c;
  j["t_valid_max_c"] = s.t_valid_max_c;
  j["hw_offs_lsb"] = s.hw_offs;
  return j;
}

}  // namespace

bool InspectOptions::IsValid(std::string* why) const {
  if (slot_a_address % kPageSize != 0 || slot_b_address % kPageSize != 0) {
    if (why) *why = "slot addresses must be multiples of the 1024-byte page";
    return false;
  }
  if (slot_a_address == slot_b_address) {
    if (why) *why = "slot A and slot B must be different pages";
    return false;
  }
  return true;
}

InspectReport InspectBin(const std::vector<uint8_t>& bytes, const InspectOptions& options) {
  InspectReport report;
  report.format = "bin";
  metro_fw_blob_info info{};
  report.slots.push_back(InspectSlot(bytes, "file", 0, options, &report.refusals, &info));
  if (SectionsLocated(report.slots[0].code) && bytes.size() > info.total_len) {
    report.refusals.push_back(fmt::format(
        "{} bytes after total_len {} (bytes 0x{:X}-0x{:X}): a .bin holds exactly one blob; "
        "expected a file of {} bytes",
        bytes.size() - info.total_len, info.total_len, info.total_len, bytes.size() - 1,
        info.total_len));
  }
  if (report.slots[0].code == METRO_FW_OK) report.active = 0;
  return report;
}

InspectReport InspectHexSegments(const std::vector<HexSegment>& segments,
                                 const InspectOptions& options) {
  InspectReport report;
  report.format = "hex";
  OutsideSlots(segments, options, &report.refusals);
  uint32_t seq[2] = {0, 0};
  for (int slot = 0; slot < 2; ++slot) {
    const uint32_t base = slot == 0 ? options.slot_a_address : options.slot_b_address;
    const char* label = slot == 0 ? "A" : "B";
    std::vector<uint8_t> page(kPageSize, 0xFF);  // what nrfjprog --sectorerase leaves
    std::vector<bool> written(kPageSize, false);
    for (const auto& seg : segments) {
      for (size_t i = 0; i < seg.bytes.size(); ++i) {
        const uint64_t a = uint64_t{seg.address} + i;
        if (a >= base && a < uint64_t{base} + kPageSize) {
          page[a - base] = seg.bytes[i];
          written[a - base] = true;
        }
      }
    }
    metro_fw_blob_info info{};
    report.slots.push_back(InspectSlot(page, label, base, options, &report.refusals, &info));
    const SlotReport& r = report.slots.back();
    if (r.code == METRO_FW_OK) seq[slot] = r.contents->seq;
    const auto first_written = [&](size_t from) {
      return static_cast<size_t>(
          std::find(written.begin() + static_cast<std::ptrdiff_t>(from), written.end(), true) -
          written.begin());
    };
    const auto last_written = [&] {
      return kPageSize - 1 -
             static_cast<size_t>(std::find(written.rbegin(), written.rend(), true) -
                                 written.rbegin());
    };
    if (first_written(0) == kPageSize) {
      report.refusals.push_back(fmt::format(
          "slot {} (0x{:05X}-0x{:05X}) is not written: nrfjprog --sectorerase leaves the tag's "
          "old slot {}, whose blob may carry a higher seq and win; expected a blob or the "
          "tombstone word 0x00000000 at 0x{:05X} (docs/calibration-blob.md section 8)",
          label, base, base + kPageSize - 1, label, base));
      continue;
    }
    const size_t end = SectionsLocated(r.code) ? info.total_len : 4;
    const bool tombstone = !SectionsLocated(r.code) && page[0] == 0 && page[1] == 0 &&
                           page[2] == 0 && page[3] == 0 && written[0] && written[1] && written[2] &&
                           written[3];
    if (!SectionsLocated(r.code) && !tombstone) {
      report.refusals.push_back(fmt::format(
          "slot {} (0x{:05X}-0x{:05X}) holds no valid blob ({}) and no tombstone: expected a "
          "valid blob or the word 0x00000000 at 0x{:05X}",
          label, base, base + kPageSize - 1, r.code_name, base));
    } else if (first_written(end) != kPageSize) {
      const size_t from = first_written(end), to = last_written();
      report.refusals.push_back(fmt::format(
          "slot {}: bytes written after the {} (0x{:05X}-0x{:05X}); expected them left erased "
          "(docs/calibration-blob.md section 1)",
          label, tombstone ? "tombstone word" : fmt::format("blob's total_len {}", end),
          base + from, base + to));
    }
  }
  // metro_fw_choose_active's rule: the larger seq, slot A on a tie.
  const bool a_ok = report.slots[0].code == METRO_FW_OK;
  const bool b_ok = report.slots[1].code == METRO_FW_OK;
  if (a_ok && (!b_ok || seq[0] >= seq[1])) {
    report.active = 0;
  } else if (b_ok) {
    report.active = 1;
  }
  return report;
}

Result<InspectReport> InspectFile(const std::string& path, const InspectOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("inspect options: " + why);
  auto text = ReadBounded(path);
  if (!text.ok()) return text.error();
  const std::string& data = text.value();
  const size_t first = data.find_first_not_of(" \t\r\n");
  if (first == std::string::npos || data[first] != ':') {
    std::vector<uint8_t> bytes(data.begin(), data.end());
    InspectReport r = InspectBin(bytes, options);
    r.file = path;
    return r;
  }
  auto segments = ReadIntelHex(data, path);
  if (!segments.ok()) return segments.error();
  InspectReport report = InspectHexSegments(segments.value(), options);
  report.file = path;
  return report;
}

std::string FormatInspect(const InspectReport& report) {
  // Each line is one record: the file name and the blob's strings are data, so their control
  // characters are escaped (a "\nresult: valid" in a label must not print as a line of its own).
  std::string out = fmt::format("{} ({})\n", EscapeControlChars(report.file), report.format);
  for (size_t i = 0; i < report.slots.size(); ++i) {
    const SlotReport& s = report.slots[i];
    out += fmt::format("slot {}{}: {} - {}{}\n", s.label,
                       s.address ? fmt::format(" @0x{:05X}", s.address) : std::string(),
                       s.code_name, EscapeControlChars(s.message),
                       static_cast<int>(i) == report.active ? " [active]" : "");
    if (!s.contents) continue;
    const BlobContents& c = *s.contents;
    out += fmt::format("  format {}.{}  seq {}  device {}  flags 0x{:02X}{}  crc32 0x{:08X}\n",
                       c.fmt_major, c.fmt_minor, c.seq, FormatDeviceId(c.device_id), c.flags,
                       c.provisional ? " (provisional)" : "", c.crc32);
    const MetaConstants& m = c.meta;
    out += fmt::format("  meta: reference '{}', tag '{}', g_local {:.6f} m/s^2, cal_time {}\n",
                       EscapeControlChars(m.reference_id), EscapeControlChars(m.tag_label),
                       m.g_local_mps2, m.cal_time_utc_s);
    out += fmt::format(
        "    calibrated {}, due {}; tool {}.{}.{} commit {}; procedure {}, k = {:.1f}\n",
        IsoDateUtc(m.cal_time_utc_s), IsoDateUtc(m.due_time_utc_s), m.tool_version >> 16,
        (m.tool_version >> 8) & 0xFF, m.tool_version & 0xFF,
        Hex(m.tool_commit.data(), m.tool_commit.size()), m.procedure_id, m.unc_k_x10 / 10.0);
    out += fmt::format("    temperature of the calibration: mean {}, min {}, max {} degC\n",
                       F32(m.temp_mean_c), F32(m.temp_min_c), F32(m.temp_max_c));
    out += fmt::format("    session_uuid {}  raw_data_sha256 {}\n",
                       Hex(m.session_uuid.data(), m.session_uuid.size()),
                       Hex(m.raw_data_sha256.data(), m.raw_data_sha256.size()));
    for (const auto& v : s.sensors) {
      const auto& sensor = v.name == std::string("accel") ? c.accel : c.gyro;
      out += fmt::format("  {}: {}", v.name, v.status_name);
      if (sensor) {
        out += fmt::format(
            "  fs_sel {} dlpf {} bits 0x{:02X}  b0 [{:.2f} {:.2f} {:.2f}] LSB  "
            "valid {:.1f}..{:.1f} C",
            sensor->fs_sel, sensor->dlpf_cfg, sensor->model_bits, sensor->b0_lsb[0],
            sensor->b0_lsb[1], sensor->b0_lsb[2], sensor->t_valid_min_c, sensor->t_valid_max_c);
      }
      out += "\n";
      if (sensor) out += SensorText(*sensor, v.name == std::string("accel"));
    }
  }
  for (const std::string& why : report.refusals) {
    out += "refused: " + EscapeControlChars(why) + "\n";
  }
  if (!report.refusals.empty()) {
    out += fmt::format("result: REFUSED ({} problem{}): do not program this file\n",
                       report.refusals.size(), report.refusals.size() == 1 ? "" : "s");
  } else {
    out += report.ok() ? "result: valid\n" : "result: NO VALID CALIBRATION\n";
  }
  return out;
}

namespace {

nlohmann::json InspectValue(const InspectReport& report) {
  nlohmann::json j;
  j["file"] = report.file;
  j["format"] = report.format;
  j["ok"] = report.ok();
  j["refusals"] = report.refusals;
  j["active_slot"] = report.active >= 0 ? nlohmann::json(report.slots[report.active].label)
                                        : nlohmann::json(nullptr);
  j["slots"] = nlohmann::json::array();
  for (const auto& s : report.slots) {
    nlohmann::json js;
    js["label"] = s.label;
    js["address"] = s.address;
    js["code"] = s.code;
    js["code_name"] = s.code_name;
    js["message"] = s.message;
    if (s.contents) {
      const BlobContents& c = *s.contents;
      js["fmt_major"] = c.fmt_major;
      js["fmt_minor"] = c.fmt_minor;
      js["seq"] = c.seq;
      js["device_id"] = FormatDeviceId(c.device_id);
      js["flags"] = c.flags;
      js["provisional"] = c.provisional;
      js["crc32"] = fmt::format("{:08X}", c.crc32);
      nlohmann::json meta;
      meta["cal_time_utc_s"] = c.meta.cal_time_utc_s;
      meta["due_time_utc_s"] = c.meta.due_time_utc_s;
      meta["cal_time_utc"] = IsoDateUtc(c.meta.cal_time_utc_s);  // ISO 8601, beside the seconds
      meta["due_time_utc"] = IsoDateUtc(c.meta.due_time_utc_s);
      meta["tool_version"] = c.meta.tool_version;
      meta["tool_commit"] = Hex(c.meta.tool_commit.data(), c.meta.tool_commit.size());
      meta["session_uuid"] = Hex(c.meta.session_uuid.data(), c.meta.session_uuid.size());
      meta["raw_data_sha256"] = Hex(c.meta.raw_data_sha256.data(), c.meta.raw_data_sha256.size());
      meta["reference_id"] = c.meta.reference_id;
      meta["g_local_mps2"] = c.meta.g_local_mps2;
      meta["temp_mean_c"] = c.meta.temp_mean_c;
      meta["temp_min_c"] = c.meta.temp_min_c;
      meta["temp_max_c"] = c.meta.temp_max_c;
      meta["procedure_id"] = c.meta.procedure_id;
      meta["unc_k_x10"] = c.meta.unc_k_x10;
      meta["tag_label"] = c.meta.tag_label;
      js["meta"] = meta;
      for (const auto& v : s.sensors) {
        const auto& sensor = v.name == std::string("accel") ? c.accel : c.gyro;
        nlohmann::json jsen = sensor ? SensorJson(*sensor) : nlohmann::json::object();
        jsen["status"] = v.status_name;
        js[v.name] = jsen;
      }
    }
    j["slots"].push_back(js);
  }
  return j;
}

}  // namespace

std::string ToJson(const InspectReport& report) { return JsonText(InspectValue(report), 2); }

}  // namespace metro::blob
