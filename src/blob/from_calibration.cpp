// SensorConstantsAt (behind SensorConstantsFromCalibration) runs these stages, in order:
//
//   inputs     CheckBlobInputs   raw-count input, a nominal full scale (unless generic), u(M)
//   tempco     CheckTempco       |b1| within the plausibility limit (docs/calibration-blob.md 3.1)
//   constants  FillConstants     M, u(M), b0, b1 and their u, the fit residual, in SI
//   validity   ApplyValidity     the temperature validity range
//   generic    GenericSection    --profile generic: section v1.0 or v2.0 and its encoding
#include "metro/blob/from_calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <tuple>

#include "metro/calibration/calibration_io.hpp"
#include "metro/core/check.hpp"
#include "metro/core/file.hpp"
#include "metro/core/utc_time.hpp"

namespace metro::blob {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSensitivityTolerance = 0.10;  // Same margin as the firmware's row-norm check.

// Output unit of the calibrator -> SI: the unit g is 9.80665 m/s^2 by definition (CGPM 1901).
double SiPerOutputUnit(ImuSensor sensor) {
  return sensor == ImuSensor::kAccel ? kStandardGravityMps2 : kPi / 180.0;
}

// Nominal sensitivity in the calibrator's output unit per LSB (the firmware's s_nom / c).
double NominalOutPerLsb(ImuSensor sensor, int fs_sel) {
  return sensor == ImuSensor::kAccel ? static_cast<double>(1 << fs_sel) / 16384.0
                                     : static_cast<double>(250 << fs_sel) / 32768.0;
}

// The MPU6050 setting (fs_sel) of a full scale in g or deg/s, or -1.
int Mpu6050FsSel(ImuSensor sensor, double full_scale) {
  for (int fs = 0; fs < 4; ++fs) {
    const double setting = sensor == ImuSensor::kAccel ? 2.0 * (1 << fs) : 250.0 * (1 << fs);
    if (full_scale == setting) return fs;
  }
  return -1;
}

bool PrintableAscii(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char ch) { return ch >= 0x20 && ch <= 0x7E; });
}

template <size_t N>
std::array<uint8_t, N> HexBytes(const std::string& hex) {
  std::array<uint8_t, N> out{};
  for (size_t i = 0; i < N && 2 * i + 1 < hex.size(); ++i) {
    out[i] = static_cast<uint8_t>(std::stoul(hex.substr(2 * i, 2), nullptr, 16));
  }
  return out;
}

bool IsHex64(const std::string& s) {
  return s.size() == 64 && std::all_of(s.begin(), s.end(), [](char ch) {
           return (ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f') || (ch >= 'A' && ch <= 'F');
         });
}

// calibration.json's date_utc (ISO 8601 UTC, core/utc_time.hpp) as the blob's u32 seconds.
Result<uint32_t> ParseDateUtc(const std::string& text) {
  const std::optional<std::time_t> t = ParseUtcIso8601(text);
  if (!t) {
    return MakeError(
        fmt::format("'date_utc' is '{}'; expected ISO 8601 UTC like 2024-05-01T12:00:00Z", text));
  }
  if (*t < 0 || *t > 0xFFFFFFFF) {
    return MakeError(
        fmt::format("'date_utc' '{}' is outside 1970..2106 (u32 seconds); expected a time from "
                    "1970-01-01T00:00:00Z to 2106-02-07T06:28:15Z, e.g. 2024-05-01T12:00:00Z",
                    text));
  }
  return static_cast<uint32_t>(*t);
}

// "metro 0.1.0" -> 0x000100 (major << 16 | minor << 8 | patch); 0 when not of that form.
uint32_t ParseToolVersion(const std::string& text) {
  const size_t space = text.rfind(' ');
  const std::string v = space == std::string::npos ? text : text.substr(space + 1);
  unsigned major = 0, minor = 0, patch = 0;
  if (std::sscanf(v.c_str(), "%u.%u.%u", &major, &minor, &patch) != 3 || major > 255 ||
      minor > 255 || patch > 255) {
    return 0;
  }
  return major << 16 | minor << 8 | patch;
}

// The firmware's validator and decoder (WriteBlob) accept the section on a tag configured as it
// says: a blob holding only it (META defaults) is written.
bool FirmwareUses(const SensorConstants& s, ImuSensor sensor) {
  BlobContents b;
  b.seq = 1;
  (sensor == ImuSensor::kAccel ? b.accel : b.gyro) = s;
  return WriteBlob(b).ok();
}

// Why no section v2.0 holds `s` (its s_nom, input and b0 as tried last), naming the figures and
// what the format holds (docs/calibration-blob.md 3.1).
// *where receives the path, in the sensor's object of calibration.json, of the value the
// refusal is about (`matrix`, a row of it, `bias[i]`, `temperature.bias_per_c[i]`; empty: the
// object).
std::string GenericRefusal(const SensorConstants& s, ImuSensor sensor, const Eigen::Matrix3d& m_c,
                           double nominal_out, const std::string& source,
                           const std::string& write_error, CalibrationPath* where) {
  const bool accel = sensor == ImuSensor::kAccel;
  const char* lsb_unit = accel ? "LSB/g" : "LSB/(deg/s)";
  const char* si_unit = accel ? "m/s^2" : "rad/s";
  const double si = SiPerOutputUnit(sensor);
  const double s_nom = *s.s_nom_si_per_lsb;
  const std::string head =
      fmt::format("the {} nominal sensitivity {:.4g} {} (from {}, profile generic)",
                  ImuSensorName(sensor), 1.0 / nominal_out, lsb_unit, source);
  const std::string tail = "; the blob format cannot represent it (docs/calibration-blob.md 3.1)";
  if (!(s_nom >= kSNomMinSiPerLsb && s_nom < kSNomMaxSiPerLsb)) {
    *where = {std::string("matrix")};
    return fmt::format(
        "{} is outside what a section v2.0 can declare, {:.4g} .. {:.4g} {} (s_nom 2^-14 .. "
        "2^-7 {} per LSB, so that M and the output fit the tag's fixed-point apply){}",
        head, si / kSNomMaxSiPerLsb, si / kSNomMinSiPerLsb, lsb_unit, si_unit, tail);
  }
  for (int i = 0; i < 3; ++i) {
    const double ratio = m_c.row(i).norm() / nominal_out;
    if (std::fabs(ratio - 1.0) > kSensitivityTolerance) {
      *where = {std::string("matrix"), static_cast<size_t>(i)};
      return fmt::format(
          "{}: row {} of M has {:.4g} {}, {:+.1f} % from it; a section holds M only when every "
          "row norm lies within +-10 % of its nominal, i.e. {:.4g} .. {:.4g} {}{}",
          head, "xyz"[i], 1.0 / m_c.row(i).norm(), lsb_unit, 100.0 * (1.0 / ratio - 1.0),
          1.0 / (nominal_out * (1.0 + kSensitivityTolerance)),
          1.0 / (nominal_out * (1.0 - kSensitivityTolerance)), lsb_unit, tail);
    }
  }
  const double bias_limit = accel ? kAccelBiasLimitLsbFs0 : kGyroBiasLimitLsbFs0;
  const double tempco_limit = TempcoLimitLsbPerC(accel, 0);
  const double d =
      std::max(std::fabs(s.t_valid_max_c - s.t_ref_c), std::fabs(s.t_valid_min_c - s.t_ref_c));
  for (size_t i = 0; i < 3; ++i) {
    const double b0_abs = s.b0_lsb[i] + (s.input == kInputOffsetBinary ? 32768.0 : 0.0);
    const double bound = std::fabs(s.b0_lsb[i]) + std::fabs(s.b1_lsb_per_c[i]) * d;
    if (bound > bias_limit) {
      *where = {std::string("bias"), i};
      return fmt::format(
          "the {} bias b0_{} = {:.6g} LSB ({:+.6g} from the signed input's zero 0, {:+.6g} from "
          "an unsigned input's mid-scale 32768; with the temperature term up to {:.6g} LSB over "
          "the validity range) is beyond the {} LSB a section holds about the input's zero "
          "(|b0| + |b1| D + |b2| D^2, section v2.0: fs_sel 0's limit in counts){}",
          ImuSensorName(sensor), "xyz"[i], b0_abs, b0_abs, b0_abs - 32768.0, bound, bias_limit,
          tail);
    }
    if (std::fabs(s.b1_lsb_per_c[i]) > tempco_limit) {
      *where = {std::string("temperature"), std::string("bias_per_c"), i};
      return fmt::format(
          "the {} temperature coefficient b1_{} = {:.6g} LSB/degC is beyond the {} LSB/degC a "
          "section v2.0 holds (|b1| + 2 |b2| D){}",
          ImuSensorName(sensor), "xyz"[i], s.b1_lsb_per_c[i], tempco_limit, tail);
    }
  }
  return fmt::format("{}: {}{}", head, write_error, tail);
}

}  // namespace

bool BlobFromCalibrationOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  if (sensor < 1) return fail(fmt::format("sensor {} must be >= 1", sensor));
  if (seq < 1 || seq > kSeqMax) return fail(fmt::format("seq {} is outside 1..{}", seq, kSeqMax));
  if (dlpf_cfg > 6) return fail(fmt::format("dlpf_cfg {} is not 0..6", dlpf_cfg));
  ValidityOptions validity{t_valid_min_c, t_valid_max_c};
  std::string range_why;
  if (!validity.IsValid(&range_why)) return fail(range_why);
  for (const auto& [fs, imu, flag, settings] :
       {std::tuple{accel_fs_g, ImuSensor::kAccel, "accel_fs_g", "2, 4, 8 or 16 g"},
        std::tuple{gyro_fs_dps, ImuSensor::kGyro, "gyro_fs_dps", "250, 500, 1000 or 2000 deg/s"}}) {
    if (!fs) continue;
    if (!(*fs > 0) || !std::isfinite(*fs)) return fail(fmt::format("{} {} must be > 0", flag, *fs));
    if (profile == SensorProfile::kMpu6050 && Mpu6050FsSel(imu, *fs) < 0) {
      return fail(
          fmt::format("{} {:g} is not an MPU6050 full-scale setting ({}); another IMU's "
                      "full scale takes profile generic",
                      flag, *fs, settings));
    }
  }
  if (reference_id.size() > 16 || !PrintableAscii(reference_id)) {
    return fail(fmt::format("reference_id '{}' must be printable ASCII of at most 16 characters",
                            reference_id));
  }
  return true;
}

const char* SensorProfileName(SensorProfile profile) {
  return profile == SensorProfile::kGeneric ? "generic" : "mpu6050";
}

std::optional<SensorProfile> ParseSensorProfile(std::string_view name) {
  if (name == "mpu6050") return SensorProfile::kMpu6050;
  if (name == "generic") return SensorProfile::kGeneric;
  return std::nullopt;
}

Result<uint8_t> NominalFsSel(ImuSensor sensor, const Eigen::Matrix3d& m,
                             const BlobFromCalibrationOptions& o) {
  const bool accel = sensor == ImuSensor::kAccel;
  const std::optional<double> declared = accel ? o.accel_fs_g : o.gyro_fs_dps;
  const char* flag = accel ? "--accel-fs-g" : "--gyro-fs-dps";
  const char* lsb_unit = accel ? "LSB/g" : "LSB/(deg/s)";
  const double row_norm = m.rowwise().norm().mean();  // output unit per LSB
  if (o.profile == SensorProfile::kMpu6050 && !declared) return InferFsSel(sensor, m);
  // The nominal (output unit per LSB) and the fs_sel that declares it.
  double nominal = row_norm;
  std::string source = "the calibration's own (mean row norm of M)";
  int fs_sel = -1;
  if (declared) {
    nominal = *declared / 32768.0;
    source = fmt::format("{} {:g}", flag, *declared);
    if (o.profile == SensorProfile::kMpu6050) {
      fs_sel = Mpu6050FsSel(sensor, *declared);
      METRO_CHECK(fs_sel >= 0);  // IsValid
      nominal = NominalOutPerLsb(sensor, fs_sel);
    }
  }
  if (fs_sel < 0) {  // generic: the nearest setting, on a log scale
    double best = 1e300;
    for (int fs = 0; fs < 4; ++fs) {
      const double d = std::fabs(std::log(nominal / NominalOutPerLsb(sensor, fs)));
      if (d < best) {
        best = d;
        fs_sel = fs;
      }
    }
  }
  const double s_nom = NominalOutPerLsb(sensor, fs_sel);
  const double ratio = row_norm / s_nom;
  if (std::fabs(ratio - 1.0) <= kSensitivityTolerance) return static_cast<uint8_t>(fs_sel);
  std::string ranges;
  for (int fs = 0; fs < 4; ++fs) {
    const double lsb = 1.0 / NominalOutPerLsb(sensor, fs);
    ranges += fmt::format("{}{:.4g} .. {:.4g}", fs == 0 ? "" : ", ",
                          lsb / (1.0 + kSensitivityTolerance), lsb / (1.0 - kSensitivityTolerance));
  }
  return MakeError(fmt::format(
      "the {} sensitivity {:.4g} {} is {:+.1f} % from the nominal {:.4g} {} of fs_sel {} "
      "(nominal from {}, profile {}); the blob format v1 cannot represent it: a section declares "
      "its nominal sensitivity as an MPU6050 FS_SEL and the tag uses M only within +-10 % of it "
      "(docs/calibration-blob.md 3.1), i.e. {} {}",
      ImuSensorName(sensor), 1.0 / row_norm, lsb_unit, 100.0 * (1.0 / ratio - 1.0), 1.0 / s_nom,
      lsb_unit, fs_sel, source, SensorProfileName(o.profile), ranges, lsb_unit));
}

Result<uint8_t> InferFsSel(ImuSensor sensor, const Eigen::Matrix3d& m) {
  const double row_norm = m.rowwise().norm().mean();
  for (int fs = 0; fs < 4; ++fs) {
    const double ratio = row_norm / NominalOutPerLsb(sensor, fs);
    if (std::fabs(ratio - 1.0) <= kSensitivityTolerance) return static_cast<uint8_t>(fs);
  }
  const bool accel = sensor == ImuSensor::kAccel;
  return MakeError(fmt::format(
      "the {} sensitivity {:.6g} {} matches no MPU6050 full-scale setting within 10 % ({})",
      ImuSensorName(sensor), 1.0 / row_norm, accel ? "LSB/g" : "LSB/(deg/s)",
      accel ? "16384, 8192, 4096 or 2048 LSB/g" : "131, 65.5, 32.8 or 16.4 LSB/(deg/s)"));
}

namespace {

// ---- SensorConstantsAt's stages -----------------------------------------------------------

// What the tag needs of the calibration: raw-count input, a nominal full scale (unless
// generic) and the uncertainty of M. fs: NominalFsSel's answer.
Status CheckBlobInputs(const SensorCalibration& c, bool generic, const Result<uint8_t>& fs,
                       CalibrationPath* where) {
  const SensorModel& model = c.model;
  const auto at = [where](CalibrationPath path) { *where = std::move(path); };
  const char* name = ImuSensorName(model.sensor);
  if (model.input_unit != "LSB") {
    at({std::string("input_unit")});
    return MakeError(
        fmt::format("{}: input_unit is '{}'; the tag applies the constants to raw counts, so the "
                    "calibration must be fitted on LSB data",
                    name, model.input_unit));
  }
  if (!fs.ok() && !generic) {
    at({std::string("matrix")});
    return MakeError(fmt::format(
        "{}: {}; another IMU: --profile generic, whose section v2.0 declares its own nominal "
        "sensitivity",
        name, fs.error().message));
  }
  if (model.kind != ModelKind::kBias && c.matrix_u.isZero(0.0)) {
    at({std::string("matrix_u")});
    return MakeError(fmt::format(
        "{}: 'matrix_u' is missing or zero; the blob stores the uncertainty of every element of M",
        name));
  }
  return Status::Ok();
}

// Plausibility (docs/calibration-blob.md 3.1): the calibrator fits no b2, so the temperature
// coefficient is |b1| on each axis.
Status CheckTempco(const SensorModel& model, uint8_t fs_sel, CalibrationPath* where) {
  const auto at = [where](CalibrationPath path) { *where = std::move(path); };
  const char* name = ImuSensorName(model.sensor);
  const bool accel = model.sensor == ImuSensor::kAccel;
  const double tempco_limit = TempcoLimitLsbPerC(accel, fs_sel);
  for (int i = 0; i < 3 && model.has_temperature; ++i) {
    const double b1 = model.bias_per_c[i];
    if (std::fabs(b1) <= tempco_limit) continue;
    const double per_unit = accel ? 1000.0 * NominalOutPerLsb(model.sensor, fs_sel)
                                  : NominalOutPerLsb(model.sensor, fs_sel);
    const char* unit = accel ? "mg/degC" : "deg/s/degC";
    at({std::string("temperature"), std::string("bias_per_c"), static_cast<size_t>(i)});
    return MakeError(fmt::format(
        "{}: the temperature coefficient b1_{} = {:.6g} LSB/degC ({:.3g} {}) exceeds the "
        "plausibility limit {} LSB/degC ({:.3g} {} at fs_sel {}; docs/calibration-blob.md "
        "3.1); expected |b1| <= {} LSB/degC: no MPU6050 drifts that fast, check the fit",
        name, "xyz"[i], b1, b1 * per_unit, unit, tempco_limit, tempco_limit * per_unit, unit,
        fs_sel, tempco_limit));
  }
  return Status::Ok();
}

// The constants in SI output units (si per output unit): M, u(M), b0, b1 and their u, the
// fit residual.
void FillConstants(const SensorCalibration& c, const Eigen::Matrix3d& m_c, double si,
                   SensorConstants* constants) {
  const SensorModel& model = c.model;
  SensorConstants& s = *constants;
  s.t_ref_c = model.has_temperature ? model.t_ref_c : 25.0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // JCGM 100:2008 5.1.2: u(c x) = c u(x) for an exact c.
      s.m[static_cast<size_t>(3 * i + j)] = si * m_c(i, j);
      s.u_m[static_cast<size_t>(3 * i + j)] = si * c.matrix_u(i, j);
    }
    const size_t a = static_cast<size_t>(i);
    s.b0_lsb[a] = model.bias[i];
    s.u_b0_lsb[a] = c.bias_u[i];
    if (model.has_temperature) {
      s.b1_lsb_per_c[a] = model.bias_per_c[i];
      s.u_b1_lsb_per_c[a] = c.bias_per_c_u[i];
    }
  }
  // The fit residual in SI: accel per-pose gravity norm (g), gyro static rate (deg/s).
  const std::string group = model.sensor == ImuSensor::kAccel ? "static_pose_norm" : "static_rate";
  const std::string unit = model.sensor == ImuSensor::kAccel ? "g" : "deg/s";
  s.resid_rms_si = 0.0;
  for (const ResidualGroup& g : c.groups) {
    if (g.kind == group && g.unit == unit) s.resid_rms_si = si * g.rms;
  }
  if (s.resid_rms_si == 0.0 && c.residual_unit == unit) s.resid_rms_si = si * c.residual_rms;
}

// The temperature validity range (and its warnings).
Status ApplyValidity(const SensorCalibration& c, const BlobFromCalibrationOptions& options,
                     SensorConstants* s, std::vector<std::string>* warnings,
                     CalibrationPath* where) {
  Result<TemperatureValidity> validity =
      TemperatureValidityRange(c, ValidityOptions{options.t_valid_min_c, options.t_valid_max_c});
  if (!validity.ok()) {  // names the sensor
    *where = CalibrationPath{std::string("static_pose_temperature")};
    return validity.error();
  }
  s->t_valid_min_c = validity.value().min_c;
  s->t_valid_max_c = validity.value().max_c;
  if (warnings != nullptr) {
    warnings->insert(warnings->end(), validity.value().warnings.begin(),
                     validity.value().warnings.end());
  }
  return Status::Ok();
}

// generic (docs/calibration-blob.md 10, "Nominal sensitivity"): a section v2.0 declaring the
// nominal, with signed input or, when only that holds the biases, unsigned counts about the
// mid-scale 32768 (b0 stored relative to it, exactly: both are integers or binary64 values far
// below 2^52); refused when neither encoding can be written.
Result<SensorConstants> GenericSection(const SensorCalibration& c,
                                       const BlobFromCalibrationOptions& options,
                                       const Eigen::Matrix3d& m_c, double si, SensorConstants s,
                                       CalibrationPath* where) {
  const SensorModel& model = c.model;
  const char* name = ImuSensorName(model.sensor);
  const bool accel = model.sensor == ImuSensor::kAccel;
  const std::optional<double> declared = accel ? options.accel_fs_g : options.gyro_fs_dps;
  const double nominal_out = declared ? *declared / 32768.0 : m_c.rowwise().norm().mean();
  const std::string source =
      declared ? fmt::format("{} {:g}", accel ? "--accel-fs-g" : "--gyro-fs-dps", *declared)
               : std::string("the calibration's own (mean row norm of M)");
  s.s_nom_si_per_lsb = si * nominal_out;
  double best = 1e300;  // the range setting the tag runs: the MPU6050 FS_SEL nearest on a log scale
  for (int f = 0; f < 4; ++f) {
    const double dist = std::fabs(std::log(nominal_out / NominalOutPerLsb(model.sensor, f)));
    if (dist < best) {
      best = dist;
      s.fs_sel = static_cast<uint8_t>(f);
    }
  }
  SensorConstants tried = s;
  std::string write_error;
  for (const uint8_t input : {kInputInt16, kInputOffsetBinary}) {
    SensorConstants t = s;
    t.input = input;
    if (input == kInputOffsetBinary) {
      for (double& b : t.b0_lsb) b -= 32768.0;
    }
    BlobContents trial;
    trial.seq = 1;
    (accel ? trial.accel : trial.gyro) = t;
    Result<std::vector<uint8_t>> w = WriteBlob(trial);
    if (w.ok()) return t;
    // report the encoding whose biases lie nearer the input's zero
    const double dev = std::fabs(t.b0_lsb[0]) + std::fabs(t.b0_lsb[1]) + std::fabs(t.b0_lsb[2]);
    const double dev_tried =
        std::fabs(tried.b0_lsb[0]) + std::fabs(tried.b0_lsb[1]) + std::fabs(tried.b0_lsb[2]);
    if (input == kInputInt16 || dev < dev_tried) {
      tried = t;
      write_error = w.error().message;
    }
  }
  return MakeError(fmt::format(
      "{}: {}", name,
      GenericRefusal(tried, model.sensor, m_c, nominal_out, source, write_error, where)));
}

Result<SensorConstants> SensorConstantsAt(const SensorCalibration& c,
                                          const BlobFromCalibrationOptions& options,
                                          std::vector<std::string>* warnings,
                                          CalibrationPath* where) {
  const SensorModel& model = c.model;
  where->clear();
  const char* name = ImuSensorName(model.sensor);
  // docs/calibration-blob.md section 10: M is calibration.json's `matrix` (the reader checked it
  // against `scale` and `misalignment`); a calibration straight from a fit has model.Matrix().
  const Eigen::Matrix3d m_c = c.M();
  const bool generic = options.profile == SensorProfile::kGeneric;
  Result<uint8_t> fs = NominalFsSel(model.sensor, m_c, options);
  if (Status st = CheckBlobInputs(c, generic, fs, where); !st.ok()) return st.error();
  const double si = SiPerOutputUnit(model.sensor);
  SensorConstants s;
  s.fs_sel = fs.ok() ? fs.value() : 0;
  s.dlpf_cfg = options.dlpf_cfg;
  s.model_bits = kModelBias;
  if (model.kind == ModelKind::kFull) s.model_bits |= kModelFullMatrix;
  if (model.has_temperature) s.model_bits |= kModelLinearT;
  if (!generic) {
    if (Status st = CheckTempco(model, s.fs_sel, where); !st.ok()) return st.error();
  }
  FillConstants(c, m_c, si, &s);
  if (Status st = ApplyValidity(c, options, &s, warnings, where); !st.ok()) return st.error();
  std::string why;
  if (!s.IsValid(&why)) return MakeError(fmt::format("{}: {}", name, why));
  if (!generic) return s;
  // generic (docs/calibration-blob.md 10, "Nominal sensitivity"): a section v1.0 when the tag
  // firmware uses one (tags with a firmware older than issue #25 accept it too), else a section
  // v2.0 declaring the nominal, with signed input or, when only that holds the biases, unsigned
  // counts about the mid-scale 32768 (b0 stored relative to it, exactly: both are integers or
  // binary64 values far below 2^52).
  if (fs.ok() && FirmwareUses(s, model.sensor)) return s;
  return GenericSection(c, options, m_c, si, s, where);
}

}  // namespace

Result<SensorConstants> SensorConstantsFromCalibration(const SensorCalibration& c,
                                                       const BlobFromCalibrationOptions& options,
                                                       std::vector<std::string>* warnings) {
  CalibrationPath where;
  return SensorConstantsAt(c, options, warnings, &where);
}

Result<BlobContents> BlobContentsFromCalibration(const Calibration& cal,
                                                 const BlobFromCalibrationOptions& o,
                                                 std::vector<std::string>* warnings) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("blob options: " + why);
  const TagCalibration* tag = cal.FindTag(o.sensor);
  if (tag == nullptr) return NoSensorError(cal, o.sensor);
  if (!tag->accel && !tag->gyro) {
    return CalibrationErrorAt(
        cal, CalibrationTagPath(cal, o.sensor),
        fmt::format("sensor {} has neither an accel nor a gyro calibration", o.sensor));
  }
  BlobContents b;
  b.seq = o.seq;
  b.device_id = o.device_id;
  b.provisional = o.provisional;
  for (const auto& [src, dst] :
       {std::pair{&tag->accel, &b.accel}, std::pair{&tag->gyro, &b.gyro}}) {
    if (!*src) continue;
    const ImuSensor imu = (*src)->model.sensor;
    // Errors about the sensor's constants point at the value in calibration.json.
    const auto at = [&](const CalibrationPath& inside, std::string message) {
      CalibrationPath path = CalibrationSensorPath(cal, o.sensor, imu);
      path.insert(path.end(), inside.begin(), inside.end());
      return CalibrationErrorAt(cal, path, std::move(message));
    };
    if ((*src)->model_check && (*src)->model_check->model_rejected) {
      const std::string what =
          fmt::format("sensor {} {}: the constants are marked model_rejected: {}", o.sensor,
                      ImuSensorName(imu), (*src)->model_check->reason);
      if (!o.accept_rejected_model) {
        return at({std::string("model_check"), std::string("model_rejected")},
                  what +
                      "; expected \"model_rejected\": false (constants of a model the data "
                      "accept: refit, e.g. calibrate fit --model auto), or "
                      "--accept-rejected-model to use these anyway");
      }
      if (warnings != nullptr) warnings->push_back(what + "; written (--accept-rejected-model)");
    }
    std::vector<std::string> sensor_warnings;
    CalibrationPath where;
    Result<SensorConstants> s = SensorConstantsAt(**src, o, &sensor_warnings, &where);
    if (!s.ok()) return at(where, fmt::format("sensor {} {}", o.sensor, s.error().message));
    *dst = s.value();
    for (const std::string& w : sensor_warnings) {
      if (warnings != nullptr) warnings->push_back(fmt::format("sensor {} {}", o.sensor, w));
    }
  }

  MetaConstants& m = b.meta;
  Result<uint32_t> t = ParseDateUtc(cal.date_utc);
  if (!t.ok()) return CalibrationErrorAt(cal, {std::string("date_utc")}, t.error().message);
  m.cal_time_utc_s = t.value();
  const uint64_t due = uint64_t{t.value()} + o.due_after_s;
  m.due_time_utc_s = static_cast<uint32_t>(std::min<uint64_t>(due, 0xFFFFFFFFu));
  m.tool_version = ParseToolVersion(cal.tool_version);
  std::string raw_sha;
  if (cal.inputs.size() == 1 && IsHex64(cal.inputs.front().sha256)) {
    raw_sha = cal.inputs.front().sha256;
  } else if (!cal.inputs.empty()) {
    std::string joined;
    for (const InputFile& f : cal.inputs) joined += (joined.empty() ? "" : "\n") + f.sha256;
    raw_sha = Sha256Hex(joined);
  }
  if (!raw_sha.empty()) m.raw_data_sha256 = HexBytes<32>(raw_sha);
  const std::string uuid_hex =
      Sha256Hex(fmt::format("{}\n{}\n{}", cal.date_utc, o.sensor, raw_sha));
  m.session_uuid = HexBytes<16>(uuid_hex);
  m.session_uuid[6] = static_cast<uint8_t>((m.session_uuid[6] & 0x0F) | 0x80);  // version 8
  m.session_uuid[8] = static_cast<uint8_t>((m.session_uuid[8] & 0x3F) | 0x80);  // RFC variant
  m.reference_id = o.reference_id;
  m.g_local_mps2 = cal.gravity_mps2;
  const SensorCalibration& first = tag->accel ? *tag->accel : *tag->gyro;
  if (first.static_pose_temperature) {
    m.temp_mean_c = first.static_pose_temperature->mean_c;
    m.temp_min_c = first.static_pose_temperature->min_c;
    m.temp_max_c = first.static_pose_temperature->max_c;
  } else {
    // No temp_c in the data: t_ref_c of a temperature model (never without temp_c), else 0.
    const double t_mean = first.model.has_temperature ? first.model.t_ref_c : 0.0;
    m.temp_mean_c = m.temp_min_c = m.temp_max_c = t_mean;
  }
  m.procedure_id = kProcedureCalibrateFit;
  const double k95 = first.coverage_factor_95 > 0 ? first.coverage_factor_95 : 2.0;
  m.unc_k_x10 = static_cast<uint8_t>(std::clamp(std::lround(10.0 * k95), 1L, 255L));
  m.tag_label = fmt::format("tag{}", o.sensor).substr(0, 8);
  if (!b.IsValid(&why)) {
    return CalibrationErrorAt(cal, CalibrationTagPath(cal, o.sensor), "calibration blob: " + why);
  }
  // The tag firmware's own check of each section (WriteBlob's), last (as WriteBlob would), so
  // that its refusal points at the sensor's object.
  for (const auto& [section, imu] :
       {std::pair{&b.accel, ImuSensor::kAccel}, std::pair{&b.gyro, ImuSensor::kGyro}}) {
    if (!*section || FirmwareUses(**section, imu)) continue;
    BlobContents alone;
    alone.seq = 1;
    (imu == ImuSensor::kAccel ? alone.accel : alone.gyro) = *section;
    return CalibrationErrorAt(cal, CalibrationSensorPath(cal, o.sensor, imu),
                              WriteBlob(alone).error().message);
  }
  return b;
}

}  // namespace metro::blob
