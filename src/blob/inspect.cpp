#include "metro/blob/inspect.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <tuple>

#include "metro/blob/intel_hex.hpp"
#include "metro/core/file.hpp"
#include "metro_fw/blob.h"

namespace metro::blob {
namespace {

// The slot as the firmware sees it: validator, then each sensor on a tag configured as the
// section itself says (fs_sel, dlpf_cfg), so only physical limits and finiteness can fail.
SlotReport InspectSlot(const std::vector<uint8_t>& bytes, const std::string& label,
                       uint32_t address, const InspectOptions& options) {
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
  if (r.code != METRO_FW_OK) return r;
  auto decoded = DecodeBlob(bytes, uint64_t{id[1]} << 32 | id[0]);
  METRO_CHECK(decoded.ok());  // the same validator accepted it a moment ago
  r.contents = std::move(decoded).value();
  for (const auto& [name, kind, off] : {std::tuple{"accel", METRO_FW_ACCEL, info.accel_off},
                                        std::tuple{"gyro", METRO_FW_GYRO, info.gyro_off}}) {
    metro_fw_config cfg{};
    cfg.device_id[0] = id[0];
    cfg.device_id[1] = id[1];
    if (off != 0 && off + 2u <= bytes.size()) {
      const uint8_t fs = std::min<uint8_t>(bytes[off], 3);
      cfg.accel_fs_sel = fs;
      cfg.gyro_fs_sel = fs;
      cfg.dlpf_cfg = bytes[off + 1];
    }
    metro_fw_sensor_cal cal{};
    METRO_CHECK(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, &cfg, &cal) ==
                METRO_FW_OK);
    // An fs_sel above 3 is a configuration no tag has: report it as a mismatch.
    int status = cal.status;
    if (off != 0 && bytes[off] > 3) status = METRO_FW_SENSOR_CONFIG_MISMATCH;
    r.sensors.push_back(SensorVerdict{name, status, SensorStatusName(status)});
  }
  return r;
}

std::string Hex(const uint8_t* p, size_t n) {
  std::string s;
  for (size_t i = 0; i < n; ++i) s += fmt::format("{:02x}", p[i]);
  return s;
}

nlohmann::json SensorJson(const SensorConstants& s) {
  nlohmann::json j;
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
  report.slots.push_back(InspectSlot(bytes, "file", 0, options));
  if (report.slots[0].code == METRO_FW_OK) report.active = 0;
  return report;
}

Result<InspectReport> InspectFile(const std::string& path, const InspectOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("inspect options: " + why);
  auto text = ReadFile(path);
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
  InspectReport report;
  report.file = path;
  report.format = "hex";
  uint32_t seq[2] = {0, 0};
  for (int slot = 0; slot < 2; ++slot) {
    const uint32_t base = slot == 0 ? options.slot_a_address : options.slot_b_address;
    std::vector<uint8_t> page(kPageSize, 0xFF);  // what nrfjprog --sectorerase leaves
    for (const auto& seg : segments.value()) {
      for (size_t i = 0; i < seg.bytes.size(); ++i) {
        const uint64_t a = uint64_t{seg.address} + i;
        if (a >= base && a < uint64_t{base} + kPageSize) page[a - base] = seg.bytes[i];
      }
    }
    report.slots.push_back(InspectSlot(page, slot == 0 ? "A" : "B", base, options));
    if (report.slots.back().code == METRO_FW_OK) seq[slot] = report.slots.back().contents->seq;
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

std::string FormatInspect(const InspectReport& report) {
  std::string out = fmt::format("{} ({})\n", report.file, report.format);
  for (size_t i = 0; i < report.slots.size(); ++i) {
    const SlotReport& s = report.slots[i];
    out +=
        fmt::format("slot {}{}: {} - {}{}\n", s.label,
                    s.address ? fmt::format(" @0x{:05X}", s.address) : std::string(), s.code_name,
                    s.message, static_cast<int>(i) == report.active ? " [active]" : "");
    if (!s.contents) continue;
    const BlobContents& c = *s.contents;
    out += fmt::format("  format {}.{}  seq {}  device {}  flags 0x{:02X}{}  crc32 0x{:08X}\n",
                       c.fmt_major, c.fmt_minor, c.seq, FormatDeviceId(c.device_id), c.flags,
                       c.provisional ? " (provisional)" : "", c.crc32);
    out += fmt::format("  meta: reference '{}', tag '{}', g_local {:.6f} m/s^2, cal_time {}\n",
                       c.meta.reference_id, c.meta.tag_label, c.meta.g_local_mps2,
                       c.meta.cal_time_utc_s);
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
    }
  }
  out += report.ok() ? "result: valid\n" : "result: NO VALID CALIBRATION\n";
  return out;
}

nlohmann::json InspectToJson(const InspectReport& report) {
  nlohmann::json j;
  j["file"] = report.file;
  j["format"] = report.format;
  j["ok"] = report.ok();
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

}  // namespace metro::blob
