#include "metro/blob/blob.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/crc.hpp>
#include <cctype>
#include <cmath>
#include <cstring>
#include <limits>
#include <tuple>
#include <utility>

#include "metro/core/device_id.hpp"
#include "metro_fw/blob.h"
#include "metro_fw/crc.h"

namespace metro::blob {

static_assert(kInputInt16 == METRO_FW_INPUT_INT16 &&
                  kInputOffsetBinary == METRO_FW_INPUT_OFFSET_BINARY &&
                  kSNomMinSiPerLsb == 1.0 / (1 << (METRO_FW_S_NOM_MAX_Q - 14)) &&
                  kSNomMaxSiPerLsb == 1.0 / (1 << (METRO_FW_S_NOM_MIN_Q - 15)),
              "blob.hpp's v2.0 constants are the firmware's (docs/calibration-blob.md 2.4)");
static_assert(kAccelTempcoLimitLsbPerCFs0 == METRO_FW_ACCEL_TEMPCO_LIMIT_LSB &&
                  kGyroTempcoLimitLsbPerCFs0 == METRO_FW_GYRO_TEMPCO_LIMIT_LSB &&
                  kTValidMinSpanC == METRO_FW_T_VALID_MIN_SPAN_C,
              "blob.hpp's plausibility limits are the firmware's (docs/calibration-blob.md 3.1)");

namespace {

constexpr size_t kHeaderLen = 32;
constexpr size_t kSectionHeaderLen = 8;
constexpr size_t kMetaBodyLen = 128;
constexpr size_t kSensorBodyLen = 176;
constexpr uint8_t kKnownModelBits =
    kModelBias | kModelFullMatrix | kModelLinearT | kModelQuadraticT | kModelHwOffsets;

void Put16(std::vector<uint8_t>& b, size_t off, uint16_t v) {
  b[off] = static_cast<uint8_t>(v & 0xFF);
  b[off + 1] = static_cast<uint8_t>(v >> 8);
}
void Put32(std::vector<uint8_t>& b, size_t off, uint32_t v) {
  for (size_t i = 0; i < 4; ++i) b[off + i] = static_cast<uint8_t>((v >> (8 * i)) & 0xFF);
}
void PutF32(std::vector<uint8_t>& b, size_t off, double v) {
  const float f = static_cast<float>(v);
  uint32_t u;
  std::memcpy(&u, &f, sizeof(u));
  Put32(b, off, u);
}
uint16_t Get16(const std::vector<uint8_t>& b, size_t off) {
  return static_cast<uint16_t>(b[off] | (b[off + 1] << 8));
}
uint32_t Get32(const std::vector<uint8_t>& b, size_t off) {
  return uint32_t{b[off]} | uint32_t{b[off + 1]} << 8 | uint32_t{b[off + 2]} << 16 |
         uint32_t{b[off + 3]} << 24;
}
double GetF32(const std::vector<uint8_t>& b, size_t off) {
  const uint32_t u = Get32(b, off);
  float f;
  std::memcpy(&f, &u, sizeof(f));
  return f;
}

// Finite once stored as binary32.
bool FiniteF32(double v) {
  return std::isfinite(v) && std::fabs(v) <= std::numeric_limits<float>::max();
}

template <size_t N>
bool AllFinite(const std::array<double, N>& a) {
  return std::all_of(a.begin(), a.end(), FiniteF32);
}
template <size_t N>
bool AllNonNegative(const std::array<double, N>& a) {
  return std::all_of(a.begin(), a.end(), [](double v) { return v >= 0.0; });
}

bool AsciiFits(const std::string& s, size_t n, const char* field, std::string* why) {
  if (s.size() > n) {
    if (why) *why = fmt::format("{} '{}' is longer than {} characters", field, s, n);
    return false;
  }
  for (char c : s) {
    if (c < 0x20 || c > 0x7E) {
      if (why)
        *why = fmt::format("{} '{}' holds a character that is not printable ASCII", field, s);
      return false;
    }
  }
  return true;
}

void PutSensor(std::vector<uint8_t>& b, size_t off, const SensorConstants& s) {
  b[off + 0] = s.fs_sel;
  b[off + 1] = s.dlpf_cfg;
  b[off + 2] = s.model_bits;
  if (s.s_nom_si_per_lsb) {  // v2.0: input encoding and declared nominal sensitivity
    b[off + 3] = s.input;
    PutF32(b, off + 172, *s.s_nom_si_per_lsb);
  }
  PutF32(b, off + 4, s.t_ref_c);
  for (size_t i = 0; i < 9; ++i) PutF32(b, off + 8 + 4 * i, s.m[i]);
  for (size_t i = 0; i < 3; ++i) {
    PutF32(b, off + 44 + 4 * i, s.b0_lsb[i]);
    PutF32(b, off + 56 + 4 * i, s.b1_lsb_per_c[i]);
    PutF32(b, off + 68 + 4 * i, s.b2_lsb_per_c2[i]);
  }
  for (size_t i = 0; i < 9; ++i) PutF32(b, off + 80 + 4 * i, s.u_m[i]);
  for (size_t i = 0; i < 3; ++i) {
    PutF32(b, off + 116 + 4 * i, s.u_b0_lsb[i]);
    PutF32(b, off + 128 + 4 * i, s.u_b1_lsb_per_c[i]);
    PutF32(b, off + 140 + 4 * i, s.u_b2_lsb_per_c2[i]);
  }
  PutF32(b, off + 152, s.resid_rms_si);
  PutF32(b, off + 156, s.t_valid_min_c);
  PutF32(b, off + 160, s.t_valid_max_c);
  for (size_t i = 0; i < 3; ++i) Put16(b, off + 164 + 2 * i, static_cast<uint16_t>(s.hw_offs[i]));
}

SensorConstants GetSensor(const std::vector<uint8_t>& b, size_t off, uint16_t version) {
  SensorConstants s;
  s.fs_sel = b[off];
  s.dlpf_cfg = b[off + 1];
  s.model_bits = b[off + 2];
  if ((version >> 8) == 2) {
    s.input = b[off + 3];
    s.s_nom_si_per_lsb = GetF32(b, off + 172);
  }
  s.t_ref_c = GetF32(b, off + 4);
  for (size_t i = 0; i < 9; ++i) s.m[i] = GetF32(b, off + 8 + 4 * i);
  for (size_t i = 0; i < 3; ++i) {
    s.b0_lsb[i] = GetF32(b, off + 44 + 4 * i);
    s.b1_lsb_per_c[i] = GetF32(b, off + 56 + 4 * i);
    s.b2_lsb_per_c2[i] = GetF32(b, off + 68 + 4 * i);
  }
  for (size_t i = 0; i < 9; ++i) s.u_m[i] = GetF32(b, off + 80 + 4 * i);
  for (size_t i = 0; i < 3; ++i) {
    s.u_b0_lsb[i] = GetF32(b, off + 116 + 4 * i);
    s.u_b1_lsb_per_c[i] = GetF32(b, off + 128 + 4 * i);
    s.u_b2_lsb_per_c2[i] = GetF32(b, off + 140 + 4 * i);
  }
  s.resid_rms_si = GetF32(b, off + 152);
  s.t_valid_min_c = GetF32(b, off + 156);
  s.t_valid_max_c = GetF32(b, off + 160);
  for (size_t i = 0; i < 3; ++i) s.hw_offs[i] = static_cast<int16_t>(Get16(b, off + 164 + 2 * i));
  return s;
}

void PutMeta(std::vector<uint8_t>& b, size_t off, const MetaConstants& m) {
  Put32(b, off + 0, m.cal_time_utc_s);
  Put32(b, off + 4, m.due_time_utc_s);
  Put32(b, off + 8, m.tool_version);
  std::copy(m.tool_commit.begin(), m.tool_commit.end(), b.begin() + off + 12);
  std::copy(m.session_uuid.begin(), m.session_uuid.end(), b.begin() + off + 32);
  std::copy(m.raw_data_sha256.begin(), m.raw_data_sha256.end(), b.begin() + off + 48);
  std::copy(m.reference_id.begin(), m.reference_id.end(), b.begin() + off + 80);
  PutF32(b, off + 96, m.g_local_mps2);
  PutF32(b, off + 100, m.temp_mean_c);
  PutF32(b, off + 104, m.temp_min_c);
  PutF32(b, off + 108, m.temp_max_c);
  Put16(b, off + 112, m.procedure_id);
  b[off + 114] = m.unc_k_x10;
  std::copy(m.tag_label.begin(), m.tag_label.end(), b.begin() + off + 116);
}

std::string GetString(const std::vector<uint8_t>& b, size_t off, size_t n) {
  std::string s(reinterpret_cast<const char*>(b.data() + off), n);
  return s.substr(0, s.find('\0'));
}

MetaConstants GetMeta(const std::vector<uint8_t>& b, size_t off) {
  MetaConstants m;
  m.cal_time_utc_s = Get32(b, off);
  m.due_time_utc_s = Get32(b, off + 4);
  m.tool_version = Get32(b, off + 8);
  std::copy_n(b.begin() + off + 12, 20, m.tool_commit.begin());
  std::copy_n(b.begin() + off + 32, 16, m.session_uuid.begin());
  std::copy_n(b.begin() + off + 48, 32, m.raw_data_sha256.begin());
  m.reference_id = GetString(b, off + 80, 16);
  m.g_local_mps2 = GetF32(b, off + 96);
  m.temp_mean_c = GetF32(b, off + 100);
  m.temp_min_c = GetF32(b, off + 104);
  m.temp_max_c = GetF32(b, off + 108);
  m.procedure_id = Get16(b, off + 112);
  m.unc_k_x10 = b[off + 114];
  m.tag_label = GetString(b, off + 116, 8);
  return m;
}

void PutSection(std::vector<uint8_t>& b, size_t off, uint16_t type, size_t body_len,
                uint16_t version = METRO_FW_SEC_VERSION_1_0) {
  Put16(b, off, type);
  Put16(b, off + 2, version);
  Put16(b, off + 4, static_cast<uint16_t>(body_len));
}

}  // namespace

bool SensorConstants::IsValid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  if (fs_sel > 3) return fail(fmt::format("fs_sel {} is not 0..3", fs_sel));
  if (dlpf_cfg > 6) return fail(fmt::format("dlpf_cfg {} is not 0..6", dlpf_cfg));
  if ((model_bits & ~kKnownModelBits) != 0) {
    return fail(fmt::format("model_bits 0x{:02X} has bits outside 0x8F", model_bits));
  }
  if (!FiniteF32(t_ref_c) || !AllFinite(m) || !AllFinite(b0_lsb) || !AllFinite(b1_lsb_per_c) ||
      !AllFinite(b2_lsb_per_c2) || !AllFinite(u_m) || !AllFinite(u_b0_lsb) ||
      !AllFinite(u_b1_lsb_per_c) || !AllFinite(u_b2_lsb_per_c2) || !FiniteF32(resid_rms_si) ||
      !FiniteF32(t_valid_min_c) || !FiniteF32(t_valid_max_c)) {
    return fail("a constant is NaN, infinite or too large for binary32");
  }
  if (!AllNonNegative(u_m) || !AllNonNegative(u_b0_lsb) || !AllNonNegative(u_b1_lsb_per_c) ||
      !AllNonNegative(u_b2_lsb_per_c2) || resid_rms_si < 0.0) {
    return fail("an uncertainty or resid_rms is negative");
  }
  if (input != kInputInt16 && input != kInputOffsetBinary) {
    return fail(fmt::format("input {} is not 0 (int16) or 1 (offset binary)", input));
  }
  if (!s_nom_si_per_lsb && input != kInputInt16) {
    return fail("an offset-binary input needs a section v2.0 (s_nom_si_per_lsb)");
  }
  if (s_nom_si_per_lsb && !(FiniteF32(*s_nom_si_per_lsb) && *s_nom_si_per_lsb > 0.0)) {
    return fail(fmt::format("s_nom_si_per_lsb {} is not a positive binary32", *s_nom_si_per_lsb));
  }
  if (!(t_valid_min_c < t_valid_max_c)) {
    return fail(fmt::format("t_valid_min_c {} is not below t_valid_max_c {}", t_valid_min_c,
                            t_valid_max_c));
  }
  return true;
}

bool MetaConstants::IsValid(std::string* why) const {
  if (!AsciiFits(reference_id, 16, "reference_id", why)) return false;
  if (!AsciiFits(tag_label, 8, "tag_label", why)) return false;
  if (!FiniteF32(g_local_mps2) || !FiniteF32(temp_mean_c) || !FiniteF32(temp_min_c) ||
      !FiniteF32(temp_max_c)) {
    if (why) *why = "a META number is NaN, infinite or too large for binary32";
    return false;
  }
  return true;
}

bool BlobContents::IsValid(std::string* why) const {
  if (seq < 1 || seq > kSeqMax) {
    if (why) *why = fmt::format("seq {} is outside 1..{}", seq, kSeqMax);
    return false;
  }
  if (!meta.IsValid(why)) return false;
  std::string sub;
  if (accel && !accel->IsValid(&sub)) {
    if (why) *why = "accel: " + sub;
    return false;
  }
  if (gyro && !gyro->IsValid(&sub)) {
    if (why) *why = "gyro: " + sub;
    return false;
  }
  return true;
}

uint32_t Crc32(const uint8_t* data, size_t size) {
  boost::crc_32_type crc;
  crc.process_bytes(data, size);
  return crc.checksum();
}

Result<std::vector<uint8_t>> WriteBlob(const BlobContents& c) {
  std::string why;
  if (!c.IsValid(&why)) return MakeError("calibration blob: " + why);
  if (!c.accel && !c.gyro) {
    return MakeError(
        "calibration blob: no sensor constants; a blob carries the accel constants, the gyro "
        "constants or both (docs/calibration-blob.md section 2)");
  }
  size_t total = kHeaderLen + kSectionHeaderLen + kMetaBodyLen + 4;
  if (c.accel) total += kSectionHeaderLen + kSensorBodyLen;
  if (c.gyro) total += kSectionHeaderLen + kSensorBodyLen;
  std::vector<uint8_t> b(total, 0);
  uint32_t flags = 0;
  auto temp_model = [](const std::optional<SensorConstants>& s) {
    return s && (s->model_bits & (kModelLinearT | kModelQuadraticT)) != 0;
  };
  if (c.accel) flags |= METRO_FW_FLAG_ACCEL;
  if (c.gyro) flags |= METRO_FW_FLAG_GYRO;
  if (temp_model(c.accel) || temp_model(c.gyro)) flags |= METRO_FW_FLAG_TEMP_MODEL;
  if (c.provisional) flags |= METRO_FW_FLAG_PROVISIONAL;
  Put32(b, 0, METRO_FW_MAGIC);
  Put16(b, 4, METRO_FW_FMT_MAJOR);
  Put16(b, 6, METRO_FW_FMT_MINOR);
  Put16(b, 8, static_cast<uint16_t>(total));
  Put16(b, 10, kHeaderLen);
  Put32(b, 12, c.seq);
  Put32(b, 16, static_cast<uint32_t>(c.device_id & 0xFFFFFFFFu));
  Put32(b, 20, static_cast<uint32_t>(c.device_id >> 32));
  Put32(b, 24, flags);
  size_t off = kHeaderLen;
  PutSection(b, off, METRO_FW_SEC_META, kMetaBodyLen);
  PutMeta(b, off + kSectionHeaderLen, c.meta);
  off += kSectionHeaderLen + kMetaBodyLen;
  for (const auto& [sensor, type] :
       {std::pair{&c.accel, METRO_FW_SEC_ACCEL}, std::pair{&c.gyro, METRO_FW_SEC_GYRO}}) {
    if (!*sensor) continue;
    PutSection(b, off, static_cast<uint16_t>(type), kSensorBodyLen,
               (*sensor)->s_nom_si_per_lsb ? METRO_FW_SEC_VERSION_2_0 : METRO_FW_SEC_VERSION_1_0);
    PutSensor(b, off + kSectionHeaderLen, **sensor);
    off += kSectionHeaderLen + kSensorBodyLen;
  }
  Put32(b, total - 4, Crc32(b.data(), total - 4));

  // The firmware must accept what we write, each sensor on a tag configured as it says.
  metro_fw_buffer buf{b.data(), static_cast<uint32_t>(b.size())};
  metro_fw_blob_info info{};
  const uint32_t id[2] = {static_cast<uint32_t>(c.device_id & 0xFFFFFFFFu),
                          static_cast<uint32_t>(c.device_id >> 32)};
  const int rc = metro_fw_blob_validate(metro_fw_buffer_read, &buf, buf.len, id, &info);
  // The writer follows the layout the validator checks; the validator's one objection can be a
  // sensor section outside the firmware's limits (METRO_FW_E_SENSOR), named below per sensor.
  METRO_CHECK(rc == METRO_FW_OK || rc == METRO_FW_E_SENSOR);
  for (const auto& [sensor, kind, name] : {std::tuple{&c.accel, METRO_FW_ACCEL, "accel"},
                                           std::tuple{&c.gyro, METRO_FW_GYRO, "gyro"}}) {
    if (!*sensor) continue;
    metro_fw_config cfg{};
    cfg.device_id[0] = id[0];
    cfg.device_id[1] = id[1];
    cfg.accel_fs_sel = kind == METRO_FW_ACCEL ? (*sensor)->fs_sel : 0;
    cfg.gyro_fs_sel = kind == METRO_FW_GYRO ? (*sensor)->fs_sel : 0;
    cfg.dlpf_cfg = (*sensor)->dlpf_cfg;
    cfg.accel_input = kind == METRO_FW_ACCEL ? (*sensor)->input : 0;
    cfg.gyro_input = kind == METRO_FW_GYRO ? (*sensor)->input : 0;
    metro_fw_sensor_cal cal{};
    METRO_CHECK(metro_fw_sensor_decode(metro_fw_buffer_read, &buf, &info, kind, &cfg, &cal) ==
                METRO_FW_OK);
    if (cal.status != METRO_FW_SENSOR_OK) {
      return MakeError(fmt::format(
          "calibration blob: the tag firmware would not use the {} constants ({}): {}", name,
          SensorStatusName(cal.status),
          cal.status != METRO_FW_SENSOR_LIMITS ? "see docs/calibration-blob.md section 3.1"
          : (*sensor)->s_nom_si_per_lsb
              ? "section v2.0: s_nom within 2^-14 .. 2^-7 SI per LSB, row norms of M within 10 "
                "% of s_nom, det(M) > 0, bias |b0| + |b1| D + |b2| D^2 within 4096 (accel) / "
                "7864 (gyro) LSB about the input's zero, temperature coefficient |b1| + 2 |b2| D "
                "within 80 / 88 LSB/degC and -40 <= t_valid_min_c, t_valid_min_c + 2 <= "
                "t_valid_max_c <= 85 are required"
              : "row norms of M within 10 % of the nominal sensitivity, det(M) > 0, bias within "
                "0.25 g / 60 deg/s, temperature coefficient |b1| + 2 |b2| D within 4.9 mg/degC "
                "/ 0.67 deg/s/degC and -40 <= t_valid_min_c, t_valid_min_c + 2 <= "
                "t_valid_max_c <= 85 are required"));
    }
  }
  if (rc != METRO_FW_OK) {
    return MakeError("calibration blob: " + FirmwareErrorName(rc) + ": " +
                     FirmwareErrorMessage(rc));
  }
  return b;
}

Result<BlobContents> DecodeBlob(const std::vector<uint8_t>& bytes,
                                std::optional<uint64_t> device_id) {
  if (bytes.size() > 0xFFFFFFFFu) return MakeError("calibration blob: larger than 4 GiB");
  metro_fw_buffer buf{bytes.data(), static_cast<uint32_t>(bytes.size())};
  uint32_t id[2] = {0, 0};
  if (device_id) {
    id[0] = static_cast<uint32_t>(*device_id & 0xFFFFFFFFu);
    id[1] = static_cast<uint32_t>(*device_id >> 32);
  } else if (bytes.size() >= 24) {
    id[0] = Get32(bytes, 16);
    id[1] = Get32(bytes, 20);
  }
  metro_fw_blob_info info{};
  const int rc = metro_fw_blob_validate(metro_fw_buffer_read, &buf, buf.len, id, &info);
  if (rc != METRO_FW_OK) {
    return MakeError(FirmwareErrorName(rc) + ": " + FirmwareErrorMessage(rc));
  }
  BlobContents c;
  c.fmt_major = info.fmt_major;
  c.fmt_minor = info.fmt_minor;
  c.seq = info.seq;
  c.device_id = uint64_t{info.device_id[1]} << 32 | info.device_id[0];
  c.flags = info.flags;
  c.crc32 = info.crc32;
  c.provisional = (info.flags & METRO_FW_FLAG_PROVISIONAL) != 0;
  if (info.meta_off != 0 && (info.meta_version >> 8) == 1) c.meta = GetMeta(bytes, info.meta_off);
  // The validator accepted the blob, so every sensor section present has major 1 or 2.
  if (info.accel_off != 0) c.accel = GetSensor(bytes, info.accel_off, info.accel_version);
  if (info.gyro_off != 0) c.gyro = GetSensor(bytes, info.gyro_off, info.gyro_version);
  return c;
}

Result<uint64_t> ParseDeviceId(std::string_view text) { return ParseDeviceIdText(text); }

std::string FormatDeviceId(uint64_t device_id) { return FormatDeviceIdText(device_id); }

std::string FirmwareErrorName(int code) {
  switch (code) {
    case METRO_FW_OK:
      return "METRO_FW_OK";
    case METRO_FW_E_ARG:
      return "METRO_FW_E_ARG";
    case METRO_FW_E_EMPTY:
      return "METRO_FW_E_EMPTY";
    case METRO_FW_E_MAGIC:
      return "METRO_FW_E_MAGIC";
    case METRO_FW_E_UNSUPPORTED:
      return "METRO_FW_E_UNSUPPORTED";
    case METRO_FW_E_BOUNDS:
      return "METRO_FW_E_BOUNDS";
    case METRO_FW_E_CRC:
      return "METRO_FW_E_CRC";
    case METRO_FW_E_FOREIGN:
      return "METRO_FW_E_FOREIGN";
    case METRO_FW_E_SEQ:
      return "METRO_FW_E_SEQ";
    case METRO_FW_E_SECTION:
      return "METRO_FW_E_SECTION";
    case METRO_FW_E_FLASH:
      return "METRO_FW_E_FLASH";
    case METRO_FW_E_VERIFY:
      return "METRO_FW_E_VERIFY";
    case METRO_FW_E_STALE_SEQ:
      return "METRO_FW_E_STALE_SEQ";
    case METRO_FW_E_FRAME:
      return "METRO_FW_E_FRAME";
    case METRO_FW_E_SENSOR:
      return "METRO_FW_E_SENSOR";
    case METRO_FW_LIVE_UNVERIFIED:
      return "METRO_FW_LIVE_UNVERIFIED";
    default:
      return fmt::format("METRO_FW_E_UNKNOWN({})", code);
  }
}

std::string FirmwareErrorMessage(int code) {
  switch (code) {
    case METRO_FW_OK:
      return "valid";
    case METRO_FW_E_ARG:
      return "invalid argument";
    case METRO_FW_E_EMPTY:
      return "empty slot (magic 0xFFFFFFFF)";
    case METRO_FW_E_MAGIC:
      return "magic is not \"ICAL\" (tombstone, torn commit or garbage)";
    case METRO_FW_E_UNSUPPORTED:
      return "fmt_major is not 1";
    case METRO_FW_E_BOUNDS:
      return "total_len or header_len out of bounds (multiple of 4, 32 <= header_len, "
             "header_len + 4 <= total_len <= 1024 and within the data)";
    case METRO_FW_E_CRC:
      return "CRC-32 mismatch";
    case METRO_FW_E_FOREIGN:
      return "device id belongs to another tag";
    case METRO_FW_E_SEQ:
      return "seq is 0 or 0xFFFFFFFF";
    case METRO_FW_E_SECTION:
      return "section walk failed (see docs/calibration-blob.md 2.2)";
    case METRO_FW_E_FLASH:
      return "flash operation failed";
    case METRO_FW_E_VERIFY:
      return "read-back differs from what was written";
    case METRO_FW_E_STALE_SEQ:
      return "seq is not above the active calibration's";
    case METRO_FW_E_FRAME:
      return "bad push frame";
    default:
      return "unknown firmware error";
  }
}

std::string SensorStatusName(int status) {
  switch (status) {
    case METRO_FW_SENSOR_OK:
      return "OK";
    case METRO_FW_SENSOR_ABSENT:
      return "ABSENT";
    case METRO_FW_SENSOR_UNSUPPORTED:
      return "UNSUPPORTED";
    case METRO_FW_SENSOR_NONFINITE:
      return "NONFINITE";
    case METRO_FW_SENSOR_BAD_MODEL:
      return "BAD_MODEL";
    case METRO_FW_SENSOR_CONFIG_MISMATCH:
      return "CONFIG_MISMATCH";
    case METRO_FW_SENSOR_LIMITS:
      return "LIMITS";
    default:
      return fmt::format("UNKNOWN({})", status);
  }
}

std::array<double, 3> ApplyConstants(const SensorConstants& c,
                                     const std::array<int16_t, 3>& raw_lsb, double temp_c) {
  double t = std::isnan(temp_c) ? c.t_ref_c : temp_c;
  t = std::clamp(t, c.t_valid_min_c, c.t_valid_max_c);
  const double dt = t - c.t_ref_c;
  std::array<double, 3> d{};
  for (size_t i = 0; i < 3; ++i) {
    const double b0 = (c.model_bits & kModelBias) ? c.b0_lsb[i] : 0.0;
    const double b1 = (c.model_bits & kModelLinearT) ? c.b1_lsb_per_c[i] : 0.0;
    const double b2 = (c.model_bits & kModelQuadraticT) ? c.b2_lsb_per_c2[i] : 0.0;
    d[i] = raw_lsb[i] - b0 - b1 * dt - b2 * dt * dt;
  }
  std::array<double, 3> y{};
  for (size_t i = 0; i < 3; ++i) {
    for (size_t j = 0; j < 3; ++j) {
      const bool use = i == j || (c.model_bits & kModelFullMatrix) != 0;
      y[i] += use ? c.m[3 * i + j] * d[j] : 0.0;
    }
  }
  return y;
}

}  // namespace metro::blob
