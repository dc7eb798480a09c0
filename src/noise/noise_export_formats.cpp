#include "noise/noise_export_formats.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

namespace metro {
namespace {

constexpr SensorKind kAcc = SensorKind::kAccelerometer;
constexpr SensorKind kGyr = SensorKind::kGyroscope;
constexpr NoiseTerm kN = NoiseTerm::kRandomWalk;
constexpr NoiseTerm kK = NoiseTerm::kRateRandomWalk;

ExportKeyGroup Scalar(SensorKind s, NoiseTerm t, std::string key,
                      ExportValueKind kind = ExportValueKind::kContinuous) {
  return {s, t, false, {{std::move(key), s, t, kind}}};
}

ExportKeyGroup PerAxis(SensorKind s, NoiseTerm t, const std::string& key, std::array<int, 3> index,
                       ExportValueKind kind) {
  ExportKeyGroup g{s, t, true, {}};
  for (int i : index) g.keys.push_back({fmt::format("{}[{}]", key, i), s, t, kind});
  return g;
}

std::vector<ExportKeyGroup> KalibrGroups(const std::string& prefix) {
  return {Scalar(kAcc, kN, prefix + "accelerometer_noise_density"),
          Scalar(kAcc, kK, prefix + "accelerometer_random_walk"),
          Scalar(kGyr, kN, prefix + "gyroscope_noise_density"),
          Scalar(kGyr, kK, prefix + "gyroscope_random_walk")};
}

// The format's own paragraph of the convention block.
std::string FormatConvention(NoiseExportFormat format, double px4_rate_hz) {
  switch (format) {
    case NoiseExportFormat::kKalibr:
      return "Kalibr imu.yaml (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model): continuous-time "
             "values, *_noise_density = metro N (random_walk), *_random_walk = metro K "
             "(rate_random_walk). Kalibr discretizes them at update_rate: sigma_d = density * "
             "sqrt(rate), sigma_bd = random_walk / sqrt(rate).";
    case NoiseExportFormat::kOpenVins:
      return "OpenVINS kalibr_imu_chain.yaml: Kalibr's continuous values under imu0 (OpenVINS "
             "discretizes with Kalibr's rule). Only the noise keys are written: merge them into "
             "your imu0 (T_i_b, the intrinsics model and matrices stay yours).";
    case NoiseExportFormat::kBasalt:
      return "basalt calibration.json (value0): continuous *_noise_std = metro N and *_bias_std "
             "= metro K per axis x, y, z (basalt takes noise_std * sqrt(imu_update_rate) as the "
             "discrete sigma). Merge these members into your calibration.json's value0.";
    case NoiseExportFormat::kVins:
      return "VINS-Mono / VINS-Fusion config: acc_n, gyr_n = metro N and acc_w, gyr_w = metro K, "
             "written as the continuous (Kalibr) values that its users put there. Its config "
             "calls them 'noise standard deviation', its authors 'discrete' (VINS-Mono issue "
             "#102), and its integration_base.h propagates them per sample (midpoint: each of "
             "two samples with V = dt/2 and noise acc_n^2; the bias with V = dt and acc_w^2), "
             "which makes acc_n = N * sqrt(2 rate) and acc_w = K * sqrt(rate) for the same "
             "covariance; both readings are given under each value. Merge into your config.";
    case NoiseExportFormat::kOrbSlam3:
      return "ORB-SLAM3 settings: IMU.Noise* = metro N, IMU.*Walk = metro K, continuous; "
             "ORB-SLAM3 discretizes with Kalibr's rule at IMU.Frequency (Noise * sqrt(f), "
             "Walk / sqrt(f)). Merge into your settings file.";
    case NoiseExportFormat::kGtsam:
      return "GTSAM PreintegrationParams / PreintegrationCombinedParams: continuous-time sigmas "
             "(names of GTSAM's ImuFactorsExample). accelerometerCovariance = I * "
             "accel_noise_sigma^2, gyroscopeCovariance = I * gyro_noise_sigma^2, "
             "biasAccCovariance = I * accel_bias_rw_sigma^2, biasOmegaCovariance = I * "
             "gyro_bias_rw_sigma^2.";
    case NoiseExportFormat::kPx4Ekf2:
      return fmt::format(
          "PX4 EKF2 parameters (nsh param set): EKF2 takes (dt * EKF2_GYR_NOISE)^2 as a "
          "prediction step's delta-angle variance and dt^2 * EKF2_GYR_B_NOISE as its bias "
          "step's delta-angle sigma (EKF/covariance.cpp), so both are continuous / sqrt(dt) = "
          "continuous * sqrt(f), at the prediction rate f = {:g} Hz (--px4-predict-rate-hz). "
          "These describe the sensor at rest: PX4's defaults carry margin for vibration.",
          px4_rate_hz);
    case NoiseExportFormat::kRos:
      return "sensor_msgs/Imu covariances (row-major 3x3, diagonal; off-diagonal 0): the "
             "per-sample variance of one message at the record's rate, N^2 * rate; the bias "
             "random walk has no place in the message.";
  }
  return {};
}

const char* kCommentOpen = "# ";

std::string Num(double v) { return fmt::format("{:.17g}", v); }

// The convention block: one line per string.
std::vector<std::string> ConventionLines(const NoiseExport& e, const std::string& source,
                                         const NoiseExportOptions& o) {
  std::vector<std::string> lines = {
      fmt::format("metro noise export, format {} (characterize noise-export)",
                  NoiseExportFormatName(e.format)),
      "source record: " + source,
      fmt::format("record sample rate: {:.10g} Hz (allan.sample_period.rate_hz)", e.rate_hz),
      "convention: " + FormatConvention(e.format, o.px4_predict_rate_hz),
      "PSD: metro N is the continuous white sigma of the two-sided PSD N^2 (IEEE Std 952-1997 "
      "Annex C); the one-sided density of a datasheet is sqrt(2) N and is not written here.",
  };
  bool per_axis = false;
  for (const ExportKeyGroup& g : ExportKeyGroups(e.format)) per_axis = per_axis || g.per_axis;
  lines.push_back(
      per_axis ? "axes: one value per axis (x, y, z), no reduction"
      : o.reduction == AxisReduction::kMax
          ? "axes: max over the axes (--axis-reduction max, the default): the largest axis value "
            "with that axis's u"
          : "axes: rms over the axes (--axis-reduction rms): sqrt(mean(v_i^2)), u by JCGM "
            "100:2008 5.1.2 with uncorrelated axes");
  lines.push_back(
      "u: standard uncertainty (k = 1) from the report's fit; 68 % interval value -/+ u, 95 % "
      "interval value -/+ 1.96 u (normal approximation)");
  for (const ExportedNoiseValue& v : e.values) {
    lines.push_back(fmt::format("{} = {:.6g} {}: {}", v.key, v.value, v.unit, v.convention));
    lines.push_back(fmt::format("  u = {:.2g}; 68 % [{:.6g}, {:.6g}]; 95 % [{:.6g}, {:.6g}]", v.u,
                                v.value - v.u, v.value + v.u, v.low95, v.high95));
    if (v.unit.find("sqrt(Hz)") != std::string::npos) {
      const bool white = v.term == NoiseTerm::kRandomWalk;
      lines.push_back(fmt::format("  discrete at {:.10g} Hz (Kalibr's rule): {} = {:.6g}",
                                  e.rate_hz, white ? "value * sqrt(rate)" : "value / sqrt(rate)",
                                  white ? DiscreteWhiteSigma(v.value, e.rate_hz)
                                        : DiscreteBiasWalkSigma(v.value, e.rate_hz)));
    }
    if (e.format == NoiseExportFormat::kVins) {  // integration_base.h (see the convention).
      lines.push_back(fmt::format(
          "  VINS integration_base.h reading at {:.10g} Hz: {} = {:.6g}", e.rate_hz,
          v.term == NoiseTerm::kRandomWalk ? "value * sqrt(2 rate)" : "value * sqrt(rate)",
          v.value * std::sqrt((v.term == NoiseTerm::kRandomWalk ? 2.0 : 1.0) * e.rate_hz)));
    }
    lines.push_back("  from: " + v.from);
  }
  return lines;
}

std::string CommentBlock(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += kCommentOpen + l + "\n";
  return s;
}

std::string MetaLines(NoiseExportFormat format, double rate_hz, const NoiseExportOptions& o,
                      const std::string& indent, const std::string& strip) {
  std::string s;
  for (const ExportMetaKey& m : ExportMetaKeys(format)) {
    const std::string key = m.key.substr(strip.size());
    if (m.kind == ExportMetaKind::kRate) s += fmt::format("{}{}: {:.10g}\n", indent, key, rate_hz);
    if (m.kind == ExportMetaKind::kTopic) s += fmt::format("{}{}: {}\n", indent, key, o.rostopic);
  }
  return s;
}

// key: value lines (Kalibr, VINS, ORB-SLAM3, GTSAM; OpenVINS under imu0).
std::string YamlText(const NoiseExport& e, const std::string& source, const NoiseExportOptions& o) {
  const bool opencv =
      e.format != NoiseExportFormat::kKalibr && e.format != NoiseExportFormat::kGtsam;
  const bool nested = e.format == NoiseExportFormat::kOpenVins;
  std::string s = opencv ? "%YAML:1.0\n" : "";
  s += CommentBlock(ConventionLines(e, source, o));
  const std::string indent = nested ? "  " : "";
  const std::string strip = nested ? "imu0." : "";
  if (nested) s += "imu0:\n";
  s += MetaLines(e.format, e.rate_hz, o, indent, strip);
  for (const ExportedNoiseValue& v : e.values) {
    s +=
        fmt::format("{}{}: {}  # [{}]\n", indent, v.key.substr(strip.size()), Num(v.value), v.unit);
  }
  return s;
}

std::string Px4Text(const NoiseExport& e, const std::string& source, const NoiseExportOptions& o) {
  std::string s = CommentBlock(ConventionLines(e, source, o));
  for (const ExportedNoiseValue& v : e.values) {
    s += fmt::format("param set {} {}\n", v.key, Num(v.value));
  }
  return s;
}

std::string RosText(const NoiseExport& e, const std::string& source, const NoiseExportOptions& o) {
  std::string s = CommentBlock(ConventionLines(e, source, o));
  for (const char* name : {"angular_velocity_covariance", "linear_acceleration_covariance"}) {
    std::array<std::string, 9> m;
    m.fill("0.0");
    for (const ExportedNoiseValue& v : e.values) {
      for (int i : {0, 4, 8}) {
        if (v.key == fmt::format("{}[{}]", name, i)) m[static_cast<size_t>(i)] = Num(v.value);
      }
    }
    s += fmt::format("{}: [{}]  # [{}]\n", name, fmt::join(m, ", "),
                     std::string(name)[0] == 'a' ? "(rad/s)^2" : "(m/s^2)^2");
  }
  return s;
}

std::string BasaltText(const NoiseExport& e, const std::string& source,
                       const NoiseExportOptions& o) {
  nlohmann::ordered_json value0;
  value0["imu_update_rate"] = std::stod(fmt::format("{:.10g}", e.rate_hz));  // As the YAML.
  for (const ExportedNoiseValue& v : e.values) {
    const std::string name = v.key.substr(7, v.key.find('[') - 7);  // "value0." ... "[i]"
    if (!value0.contains(name)) value0[name] = nlohmann::ordered_json::array();
    value0[name].push_back(v.value);
  }
  nlohmann::ordered_json root;
  root["value0"] = value0;
  root["metro_convention"] = ConventionLines(e, source, o);
  return root.dump(2) + "\n";
}

}  // namespace

const char* NoiseTermSymbol(NoiseTerm term) {
  switch (term) {
    case NoiseTerm::kQuantization:
      return "Q";
    case NoiseTerm::kRandomWalk:
      return "N";
    case NoiseTerm::kBiasInstability:
      return "B";
    case NoiseTerm::kRateRandomWalk:
      return "K";
    case NoiseTerm::kRateRamp:
      return "R";
  }
  return "?";
}

std::vector<ExportKeyGroup> ExportKeyGroups(NoiseExportFormat format) {
  using K = ExportValueKind;
  switch (format) {
    case NoiseExportFormat::kKalibr:
      return KalibrGroups("");
    case NoiseExportFormat::kOpenVins:
      return KalibrGroups("imu0.");
    case NoiseExportFormat::kBasalt:
      return {PerAxis(kAcc, kN, "value0.accel_noise_std", {0, 1, 2}, K::kContinuous),
              PerAxis(kGyr, kN, "value0.gyro_noise_std", {0, 1, 2}, K::kContinuous),
              PerAxis(kAcc, kK, "value0.accel_bias_std", {0, 1, 2}, K::kContinuous),
              PerAxis(kGyr, kK, "value0.gyro_bias_std", {0, 1, 2}, K::kContinuous)};
    case NoiseExportFormat::kVins:
      return {Scalar(kAcc, kN, "acc_n"), Scalar(kGyr, kN, "gyr_n"), Scalar(kAcc, kK, "acc_w"),
              Scalar(kGyr, kK, "gyr_w")};
    case NoiseExportFormat::kOrbSlam3:
      return {Scalar(kGyr, kN, "IMU.NoiseGyro"), Scalar(kAcc, kN, "IMU.NoiseAcc"),
              Scalar(kGyr, kK, "IMU.GyroWalk"), Scalar(kAcc, kK, "IMU.AccWalk")};
    case NoiseExportFormat::kGtsam:
      return {Scalar(kAcc, kN, "accel_noise_sigma"), Scalar(kGyr, kN, "gyro_noise_sigma"),
              Scalar(kAcc, kK, "accel_bias_rw_sigma"), Scalar(kGyr, kK, "gyro_bias_rw_sigma")};
    case NoiseExportFormat::kPx4Ekf2:
      return {Scalar(kGyr, kN, "EKF2_GYR_NOISE", K::kPx4PerStep),
              Scalar(kAcc, kN, "EKF2_ACC_NOISE", K::kPx4PerStep),
              Scalar(kGyr, kK, "EKF2_GYR_B_NOISE", K::kPx4PerStep),
              Scalar(kAcc, kK, "EKF2_ACC_B_NOISE", K::kPx4PerStep)};
    case NoiseExportFormat::kRos:
      return {PerAxis(kGyr, kN, "angular_velocity_covariance", {0, 4, 8}, K::kSampleVariance),
              PerAxis(kAcc, kN, "linear_acceleration_covariance", {0, 4, 8}, K::kSampleVariance)};
  }
  return {};
}

std::vector<ExportMetaKey> ExportMetaKeys(NoiseExportFormat format) {
  switch (format) {
    case NoiseExportFormat::kKalibr:
      return {{"rostopic", ExportMetaKind::kTopic}, {"update_rate", ExportMetaKind::kRate}};
    case NoiseExportFormat::kOpenVins:
      return {{"imu0.rostopic", ExportMetaKind::kTopic},
              {"imu0.update_rate", ExportMetaKind::kRate}};
    case NoiseExportFormat::kBasalt:
      return {{"value0.imu_update_rate", ExportMetaKind::kRate}};
    case NoiseExportFormat::kOrbSlam3:
      return {{"IMU.Frequency", ExportMetaKind::kRate}};
    case NoiseExportFormat::kRos: {
      std::vector<ExportMetaKey> zeros;
      for (const char* name : {"angular_velocity_covariance", "linear_acceleration_covariance"}) {
        for (int i : {1, 2, 3, 5, 6, 7}) {
          zeros.push_back({fmt::format("{}[{}]", name, i), ExportMetaKind::kZero});
        }
      }
      return zeros;
    }
    case NoiseExportFormat::kVins:
    case NoiseExportFormat::kGtsam:
    case NoiseExportFormat::kPx4Ekf2:
      return {};
  }
  return {};
}

std::string ExportUnit(const ExportKeySpec& spec) {
  const bool gyro = spec.sensor == SensorKind::kGyroscope;
  const std::string q = gyro ? "rad/s" : "m/s^2";
  const bool white = spec.term == NoiseTerm::kRandomWalk;
  switch (spec.kind) {
    case ExportValueKind::kContinuous:
      return white ? q + "/sqrt(Hz)" : (gyro ? "rad/s^2/sqrt(Hz)" : "m/s^3/sqrt(Hz)");
    case ExportValueKind::kPx4PerStep:
      return white ? q : (gyro ? "rad/s^2" : "m/s^3");
    case ExportValueKind::kSampleVariance:
      return "(" + q + ")^2";
  }
  return {};
}

std::string ExportConvention(const ExportKeySpec& spec, double px4_rate_hz) {
  const bool white = spec.term == NoiseTerm::kRandomWalk;
  switch (spec.kind) {
    case ExportValueKind::kContinuous:
      return white ? "continuous white sigma = metro N (random_walk; two-sided PSD N^2, not the "
                     "one-sided density sqrt(2) N)"
                   : "continuous bias random walk = metro K (rate_random_walk)";
    case ExportValueKind::kPx4PerStep:
      return fmt::format("{} * sqrt(f) at the EKF2 prediction rate f = {:g} Hz",
                         white ? "metro N" : "metro K", px4_rate_hz);
    case ExportValueKind::kSampleVariance:
      return "per-sample variance N^2 * rate at the record's rate";
  }
  return {};
}

std::string ExportText(const NoiseExport& values, const std::string& source,
                       const NoiseExportOptions& options) {
  switch (values.format) {
    case NoiseExportFormat::kBasalt:
      return BasaltText(values, source, options);
    case NoiseExportFormat::kPx4Ekf2:
      return Px4Text(values, source, options);
    case NoiseExportFormat::kRos:
      return RosText(values, source, options);
    default:
      return YamlText(values, source, options);
  }
}

}  // namespace metro
