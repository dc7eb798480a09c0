// Calibration constants used by the blob tests: a plausible MPU6050 at fs_sel 0.
#pragma once

#include "metro/blob/blob.hpp"

namespace metro::blob::testing {

inline constexpr uint64_t kDeviceId = 0x9ABCDEF012345678ull;

inline SensorConstants Accel() {
  SensorConstants s;
  const double k = 9.80665 / 16384.0;
  s.fs_sel = 0;
  s.dlpf_cfg = 3;
  s.model_bits = kModelBias | kModelFullMatrix | kModelLinearT | kModelQuadraticT;
  s.t_ref_c = 24.5;
  s.m = {1.012 * k, 0.003 * k,  -0.002 * k, 0.001 * k, 0.991 * k,
         0.004 * k, -0.001 * k, 0.0,        1.004 * k};
  s.b0_lsb = {150.25, -75.5, 310.0};
  s.b1_lsb_per_c = {1.25, -0.75, 2.5};
  s.b2_lsb_per_c2 = {0.0125, 0.0, -0.025};
  s.u_m = {2e-7, 1e-8, 1e-8, 1e-8, 2e-7, 1e-8, 1e-8, 1e-8, 2e-7};
  s.u_b0_lsb = {1.5, 1.5, 2.5};
  s.u_b1_lsb_per_c = {0.05, 0.05, 0.08};
  s.u_b2_lsb_per_c2 = {0.001, 0.001, 0.002};
  s.resid_rms_si = 0.0081;
  s.t_valid_min_c = 5.0;
  s.t_valid_max_c = 45.0;
  s.hw_offs = {-1234, 567, 8901};
  return s;
}

inline SensorConstants Gyro() {
  SensorConstants s;
  const double k = 250.0 / 32768.0 * 3.14159265358979323846 / 180.0;
  s.fs_sel = 0;
  s.dlpf_cfg = 3;
  s.model_bits = kModelBias | kModelFullMatrix | kModelLinearT;
  s.t_ref_c = 24.5;
  s.m = {0.985 * k, 0.012 * k, 0.0, -0.011 * k, 1.021 * k, 0.002 * k, 0.0, 0.006 * k, 1.003 * k};
  s.b0_lsb = {-42.0, 27.5, 11.0};
  s.b1_lsb_per_c = {0.35, -0.25, 0.15};
  s.u_b0_lsb = {0.4, 0.4, 0.5};
  s.t_valid_min_c = 5.0;
  s.t_valid_max_c = 45.0;
  return s;
}

inline BlobContents Contents(uint32_t seq = 17) {
  BlobContents c;
  c.seq = seq;
  c.device_id = kDeviceId;
  c.meta.cal_time_utc_s = 1780000000;
  c.meta.due_time_utc_s = 1811536000;
  c.meta.tool_version = 0x000100;
  for (size_t i = 0; i < 20; ++i) c.meta.tool_commit[i] = static_cast<uint8_t>(0xA0 + i);
  for (size_t i = 0; i < 16; ++i) c.meta.session_uuid[i] = static_cast<uint8_t>(i);
  for (size_t i = 0; i < 32; ++i) c.meta.raw_data_sha256[i] = static_cast<uint8_t>(255 - i);
  c.meta.reference_id = "LAB-REF-0042";
  c.meta.g_local_mps2 = 9.8101;
  c.meta.temp_mean_c = 24.0;
  c.meta.temp_min_c = 6.0;
  c.meta.temp_max_c = 44.0;
  c.meta.procedure_id = 3;
  c.meta.unc_k_x10 = 20;
  c.meta.tag_label = "TAG-07";
  c.accel = Accel();
  c.gyro = Gyro();
  return c;
}

}  // namespace metro::blob::testing
