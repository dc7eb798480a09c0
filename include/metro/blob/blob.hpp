// The calibration blob (format v1, docs/calibration-blob.md): the writer from plain
// calibration constants, the decoder, and the model in double precision.
//
// Model, raw int16 counts in, SI out (accelerometer m/s^2, gyroscope rad/s):
//
//   y = M * (r - b0 - b1*dT - b2*dT^2),  dT = clamp(T, t_valid_min_c, t_valid_max_c) - t_ref_c
//
// r is the raw sample in counts about the input's zero (int16; for a section v2.0 with
// offset-binary input the unsigned ADC word minus 32768, issue #25).
// Bias is removed before scaling, in raw counts (LSB); M (row-major, SI per LSB) holds the
// nominal sensitivity, scale, misalignment and any sensor-to-body rotation. M = diag(s_nom),
// b = 0 is identity. Terms whose model bit is clear are not applied. Uncertainties are standard
// uncertainties (k = 1) in the units of their constants.
//
// Validation uses the firmware's own C code (firmware/src), so the host accepts exactly what a
// tag accepts. This layer does not know calibration.json; the mapping lives above it.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"

namespace metro::blob {

inline constexpr uint32_t kSlotAAddress = 0x3B000;
inline constexpr uint32_t kSlotBAddress = 0x3B400;
inline constexpr uint32_t kPageSize = 1024;
inline constexpr uint32_t kV1TotalLen = 540;
inline constexpr uint32_t kSeqMax = 0xFFFFFFFE;

// Model bits of a sensor section.
inline constexpr uint8_t kModelBias = 0x01;
inline constexpr uint8_t kModelFullMatrix = 0x02;
inline constexpr uint8_t kModelLinearT = 0x04;
inline constexpr uint8_t kModelQuadraticT = 0x08;
inline constexpr uint8_t kModelHwOffsets = 0x80;

// Plausibility limits of section 3.1 that the firmware's validator applies (the same values as
// firmware/include/metro_fw/blob.h, checked at compile time): the temperature coefficient of
// the bias, |b1| + 2 |b2| D (D = max |t_valid - t_ref_c|), at most this many LSB/degC at
// fs_sel 0, halved per fs_sel step (4.9 mg/degC, 0.67 deg/s/degC: twice the steepest slope
// the MPU6050 datasheet allows around 25 degC); a validity range at least 2 degC wide.
inline constexpr int kAccelTempcoLimitLsbPerCFs0 = 80;
inline constexpr int kGyroTempcoLimitLsbPerCFs0 = 88;
inline constexpr double kTValidMinSpanC = 2.0;

// The temperature-coefficient limit in LSB/degC of the accelerometer (accel) or gyroscope at
// fs_sel 0..3.
inline double TempcoLimitLsbPerC(bool accel, int fs_sel) {
  return (accel ? kAccelTempcoLimitLsbPerCFs0 : kGyroTempcoLimitLsbPerCFs0) >> fs_sel;
}

// Raw input encodings of a sensor section v2.0 (docs/calibration-blob.md 2.4): the tag's
// driver hands the applies signed counts about the input's zero, and b0 is relative to it.
inline constexpr uint8_t kInputInt16 = 0;         // two's complement int16, zero at 0
inline constexpr uint8_t kInputOffsetBinary = 1;  // unsigned 16-bit ADC, zero at 32768
// The nominal sensitivity a section v2.0 may declare, SI per LSB: 2^-14 <= s_nom < 2^-7
// (firmware METRO_FW_S_NOM_MIN_Q / _MAX_Q). In v2.0 the bias and temperature-coefficient limits
// are fs_sel 0's in counts whatever fs_sel: 4096 / 7864 LSB, 80 / 88 LSB/degC.
inline constexpr double kSNomMinSiPerLsb = 1.0 / 16384.0;
inline constexpr double kSNomMaxSiPerLsb = 1.0 / 128.0;
inline constexpr int kAccelBiasLimitLsbFs0 = 4096;  // 0.25 g at 16384 LSB/g
inline constexpr int kGyroBiasLimitLsbFs0 = 7864;   // 60 deg/s at 131.072 LSB/(deg/s)

// Constants of one sensor (ACCEL or GYRO section body, 176 bytes). A section v1.0 declares its
// nominal sensitivity as the MPU6050 FS_SEL; with s_nom_si_per_lsb set the writer emits a
// section v2.0 (issue #25) that declares s_nom and the input encoding itself.
struct SensorConstants {
  uint8_t fs_sel = 0;      // MPU6050 FS_SEL, 0..3 (v2.0: the range setting the tag must run)
  uint8_t dlpf_cfg = 0;    // MPU6050 DLPF_CFG, 0..6
  uint8_t model_bits = 0;  // kModel* bits
  // v2.0 only: the declared nominal sensitivity (m/s^2 or rad/s per LSB) and kInput*.
  std::optional<double> s_nom_si_per_lsb;
  uint8_t input = kInputInt16;
  double t_ref_c = 25.0;
  std::array<double, 9> m{};  // row-major, SI per LSB
  std::array<double, 3> b0_lsb{}, b1_lsb_per_c{}, b2_lsb_per_c2{};
  std::array<double, 9> u_m{};  // standard uncertainties, k = 1, units of the constants
  std::array<double, 3> u_b0_lsb{}, u_b1_lsb_per_c{}, u_b2_lsb_per_c2{};
  double resid_rms_si = 0.0;  // m/s^2 or rad/s
  double t_valid_min_c = -40.0;
  double t_valid_max_c = 85.0;
  std::array<int16_t, 3> hw_offs{};  // MPU6050 offset register values

  // fs_sel <= 3, dlpf_cfg <= 6, known model bits, every number finite in binary32,
  // uncertainties and resid_rms >= 0, t_valid_min_c < t_valid_max_c; input kInputInt16 or
  // kInputOffsetBinary, and kInputInt16 without s_nom_si_per_lsb (v1.0 has no input field).
  bool IsValid(std::string* why) const;
};

// META section body (128 bytes): traceability carried by the tag.
struct MetaConstants {
  uint32_t cal_time_utc_s = 0;
  uint32_t due_time_utc_s = 0;
  uint32_t tool_version = 0;  // major << 16 | minor << 8 | patch
  std::array<uint8_t, 20> tool_commit{};
  std::array<uint8_t, 16> session_uuid{};
  std::array<uint8_t, 32> raw_data_sha256{};
  std::string reference_id;  // ASCII, at most 16 characters
  double g_local_mps2 = 9.80665;
  double temp_mean_c = 0.0;
  double temp_min_c = 0.0;
  double temp_max_c = 0.0;
  uint16_t procedure_id = 0;
  uint8_t unc_k_x10 = 20;  // coverage factor x 10 used in the report
  std::string tag_label;   // ASCII, at most 8 characters

  bool IsValid(std::string* why) const;
};

// Everything a v1 blob holds.
struct BlobContents {
  uint32_t seq = 0;        // 1 .. kSeqMax
  uint64_t device_id = 0;  // (FICR DEVICEID[1] << 32) | DEVICEID[0]
  bool provisional = false;
  MetaConstants meta;
  std::optional<SensorConstants> accel;
  std::optional<SensorConstants> gyro;
  // Read back by DecodeBlob only (ignored by WriteBlob).
  uint16_t fmt_major = 1;
  uint16_t fmt_minor = 0;
  uint32_t flags = 0;
  uint32_t crc32 = 0;

  bool IsValid(std::string* why) const;
};

// Writes the v1 blob (v1 map: header, META, ACCEL, GYRO, CRC; an absent sensor is left out).
// Fails with a message if the contents are invalid, or if the firmware, configured with each
// sensor's own fs_sel and dlpf_cfg, would not use a sensor (physical limits, section 3.1).
Result<std::vector<uint8_t>> WriteBlob(const BlobContents& contents);

// Validates with the firmware's rules against the blob's own device id (or `device_id` when
// given) and decodes every field. Errors name the firmware code, e.g.
// "METRO_FW_E_CRC: CRC-32 mismatch".
Result<BlobContents> DecodeBlob(const std::vector<uint8_t>& bytes,
                                std::optional<uint64_t> device_id = std::nullopt);

// CRC-32/ISO-HDLC (zlib's) computed with Boost.CRC, independent of the firmware's.
uint32_t Crc32(const uint8_t* data, size_t size);

// Device id text <-> device id: metro::ParseDeviceIdText (core/device_id.hpp: 16 hex digits
// DEVICEID[1] then DEVICEID[0], or nrfjprog --memrd's two words DEVICEID[0] DEVICEID[1], with
// or without 0x) and "0123456789ABCDEF".
Result<uint64_t> ParseDeviceId(std::string_view text);
std::string FormatDeviceId(uint64_t device_id);

// Name and description of a firmware error code, e.g. "METRO_FW_E_CRC", "CRC-32 mismatch".
std::string FirmwareErrorName(int code);
std::string FirmwareErrorMessage(int code);

// Name of a firmware sensor status, e.g. "LIMITS".
std::string SensorStatusName(int status);

// The model of the header comment in double precision, with the firmware's temperature clamp
// (a NaN temperature counts as t_ref_c) and model bits. raw_lsb are signed counts about the
// input's zero (for kInputOffsetBinary the ADC word minus 32768).
std::array<double, 3> ApplyConstants(const SensorConstants& c,
                                     const std::array<int16_t, 3>& raw_lsb, double temp_c);

}  // namespace metro::blob
