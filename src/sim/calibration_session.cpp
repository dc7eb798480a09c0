// SimulateCalibrationSession runs these stages, in this order:
//
//   truth     DrawImuTruth (or the given one)    the sensor models, temperature reference
//   timeline  PoseGravityDirections, Timeline    poses (tilted), hand moves, dwells, table
//                                                runs
//   samples   Sample                             true force and rate, readings through the
//                                                inverse model, noise, counts, saturation
//   session   AssembleSession                    the session's columns and its one tag
#include "metro/sim/calibration_session.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <pcg_random.hpp>
#include <random>

namespace metro {

namespace {

constexpr double kPi = 3.14159265358979323846;

double Uniform(pcg64& rng, double half_width) {
  std::uniform_real_distribution<double> d(-half_width, half_width);
  return d(rng);
}

std::vector<Eigen::Vector3d> PoseDirections(PoseSet set, int n) {
  std::vector<Eigen::Vector3d> out;
  if (set == PoseSet::kCube || set == PoseSet::kFaces) {
    std::vector<Eigen::Vector3d> cube;
    for (int a = 0; a < 3; ++a) {
      for (int s : {1, -1}) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        v[a] = s;
        cube.push_back(v);
      }
    }
    for (int x : {1, -1}) {
      for (int y : {1, -1}) {
        for (int z : {1, -1}) cube.push_back(Eigen::Vector3d(x, y, z).normalized());
      }
    }
    for (int a = 0; a < 3; ++a) {
      for (int s1 : {1, -1}) {
        for (int s2 : {1, -1}) {
          Eigen::Vector3d v = Eigen::Vector3d::Zero();
          v[a] = s1;
          v[(a + 1) % 3] = s2;
          cube.push_back(v.normalized());
        }
      }
    }
    const size_t distinct = set == PoseSet::kFaces ? 6 : cube.size();
    for (int i = 0; i < n; ++i) out.push_back(cube[static_cast<size_t>(i) % distinct]);
    return out;
  }
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double f = (i + 0.5) / n;
    const double z = set == PoseSet::kSphere ? 1.0 - 2.0 * f : 0.5 + 0.5 * f;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.push_back(Eigen::Vector3d(r * std::cos(golden * i), r * std::sin(golden * i), z));
  }
  return out;
}

// A piece of the timeline: the body orientation R_wb(tau) for tau in [0, duration_s].
struct Phase {
  enum Kind { kStill, kTable, kMove } kind = kStill;
  double duration_s = 0;
  Eigen::Matrix3d r0 = Eigen::Matrix3d::Identity();
  double rate_dps = 0;                              // kTable
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  // kMove, body frame
  double angle_rad = 0;                             // kMove

  Eigen::Matrix3d At(double tau) const {
    switch (kind) {
      case kStill:
        return r0;
      case kTable:
        return Eigen::AngleAxisd(rate_dps * kPi / 180.0 * tau, Eigen::Vector3d::UnitZ())
                   .toRotationMatrix() *
               r0;
      case kMove: {
        const double s = std::clamp(tau / duration_s, 0.0, 1.0);
        const double th = angle_rad * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);  // Min jerk.
        return r0 * Eigen::AngleAxisd(th, axis).toRotationMatrix();
      }
    }
    return r0;
  }
  double TableRate() const { return kind == kTable ? rate_dps : 0.0; }
};

}  // namespace

bool SimulationOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!(rate_hz > 0)) return fail("rate_hz must be > 0");
  if (poses < 1) return fail("poses must be >= 1");
  if (!(dwell_s > 0) || !(move_s > 0)) return fail("dwell_s and move_s must be > 0");
  if (!(accel_fs_g > 0) || !(gyro_fs_dps > 0)) return fail("full-scale settings must be > 0");
  if (!(gravity_mps2 > 0)) return fail("gravity_mps2 must be > 0");
  if (!(accel_noise_ug_rthz >= 0) || !(gyro_noise_dps_rthz >= 0) || !(bandwidth_hz > 0)) {
    return fail("noise densities must be >= 0 and bandwidth_hz > 0");
  }
  if (!(table_run_s > 0)) return fail("table_run_s must be > 0");
  if (sensor < 1) return fail("sensor must be >= 1");
  if (!(pose_tilt_deg >= 0 && pose_tilt_deg <= 45)) return fail("pose_tilt_deg must be 0 .. 45");
  if (!(accel_cross_axis >= 0 && accel_cross_axis <= 0.1) ||
      !(gyro_cross_axis >= 0 && gyro_cross_axis <= 0.1)) {
    return fail("cross-axis half-widths must be within 0 .. 0.1 (10 %)");
  }
  return true;
}

ImuTruth DrawImuTruth(uint64_t seed, double accel_fs_g, double gyro_fs_dps, bool temperature,
                      double accel_cross_axis, double gyro_cross_axis) {
  pcg64 rng(seed);
  ImuTruth t;
  SensorModel& a = t.accel;
  a.sensor = ImuSensor::kAccel;
  a.kind = ModelKind::kFull;
  a.input_unit = "LSB";
  a.output_unit = std::string(OutputUnit(ImuSensor::kAccel).symbol);
  const double lsb_per_g = 1.0 / NominalScale(ImuSensor::kAccel, "LSB", accel_fs_g).value();
  // Drawn z, y, x: the order g++ evaluates a call's arguments in (C++ leaves it unspecified;
  // clang goes left to right), with which every bundled session was simulated. Named draws
  // make the same seed give the same session under either compiler.
  const double bias_z_g = Uniform(rng, 0.080);
  const double bias_y_g = Uniform(rng, 0.050);
  const double bias_x_g = Uniform(rng, 0.050);
  a.bias = Eigen::Vector3d(bias_x_g, bias_y_g, bias_z_g) * lsb_per_g;
  for (int i = 0; i < 3; ++i) a.scale[i] = (1.0 + Uniform(rng, 0.03)) / lsb_per_g;
  a.misalignment = {Uniform(rng, accel_cross_axis), Uniform(rng, accel_cross_axis),
                    Uniform(rng, accel_cross_axis)};
  SensorModel& g = t.gyro;
  g.sensor = ImuSensor::kGyro;
  g.kind = ModelKind::kFull;
  g.input_unit = "LSB";
  g.output_unit = std::string(OutputUnit(ImuSensor::kGyro).symbol);
  const double lsb_per_dps = 1.0 / NominalScale(ImuSensor::kGyro, "LSB", gyro_fs_dps).value();
  for (int i = 0; i < 3; ++i) g.bias[i] = Uniform(rng, 20.0) * lsb_per_dps;
  for (int i = 0; i < 3; ++i) g.scale[i] = (1.0 + Uniform(rng, 0.03)) / lsb_per_dps;
  g.misalignment.clear();
  for (int i = 0; i < 6; ++i) g.misalignment.push_back(Uniform(rng, gyro_cross_axis));
  if (temperature) {
    a.has_temperature = true;
    g.has_temperature = true;
    for (int i = 0; i < 3; ++i) {
      a.bias_per_c[i] = Uniform(rng, 0.5e-3) * lsb_per_g;
      g.bias_per_c[i] = Uniform(rng, 0.16) * lsb_per_dps;
    }
  }
  return t;
}

namespace {

// ---- SimulateCalibrationSession's stages --------------------------------------------------

// The poses' gravity directions, each tilted by up to pose_tilt_deg (its own generator).
std::vector<Eigen::Vector3d> PoseGravityDirections(const SimulationOptions& o) {
  std::vector<Eigen::Vector3d> dirs = PoseDirections(o.pose_set, o.poses);
  if (o.pose_tilt_deg > 0) {
    pcg64 tilt_rng(o.seed ^ 0x5851f42d4c957f2dULL);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (Eigen::Vector3d& u : dirs) {
      const Eigen::Vector3d e1 = u.unitOrthogonal(), e2 = u.cross(e1);
      const double azimuth = 2.0 * kPi * unit(tilt_rng);
      const double angle = o.pose_tilt_deg * kPi / 180.0 * unit(tilt_rng);
      const Eigen::Vector3d axis = std::cos(azimuth) * e1 + std::sin(azimuth) * e2;
      u = Eigen::AngleAxisd(angle, axis) * u;
    }
  }
  return dirs;
}

// The timeline: per pose a hand move from the previous one (to a random heading), a still
// dwell, and each table run with the still stop after it.
std::vector<Phase> Timeline(const SimulationOptions& o, const std::vector<Eigen::Vector3d>& dirs,
                            pcg64* rng) {
  std::uniform_real_distribution<double> heading(-kPi, kPi);
  std::vector<Phase> phases;
  Eigen::Matrix3d current = Eigen::Matrix3d::Identity();
  for (size_t i = 0; i < dirs.size(); ++i) {
    const Eigen::Matrix3d align =
        Eigen::Quaterniond::FromTwoVectors(dirs[i], Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d target =
        Eigen::AngleAxisd(heading(*rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * align;
    if (i > 0) {
      Phase m;
      m.kind = Phase::kMove;
      m.duration_s = o.move_s;
      m.r0 = current;
      const Eigen::AngleAxisd rel(current.transpose() * target);
      m.axis = rel.axis();
      m.angle_rad = rel.angle();
      phases.push_back(m);
    }
    current = target;
    Phase still;
    still.duration_s = i == 0 ? 2.0 * o.dwell_s : o.dwell_s;
    still.r0 = current;
    phases.push_back(still);
    for (double rate : o.table_rates_dps) {
      Phase run;
      run.kind = Phase::kTable;
      run.duration_s = o.table_run_s;
      run.r0 = current;
      run.rate_dps = rate;
      phases.push_back(run);
      current = run.At(o.table_run_s);
      Phase stop;
      stop.duration_s = o.dwell_s;
      stop.r0 = current;
      phases.push_back(stop);
    }
  }
  return phases;
}

// The eight columns: ax ay az gx gy gz (raw counts) temp table.
using SimColumnsData = std::array<std::vector<double>, 8>;

// Every sample along the timeline: the true specific force and rate, the readings through
// the truth's inverse model with noise, rounded and saturated as counts.
// Three standard normal draws as x, y, z, drawn z first (the order of g++'s argument
// evaluation, with which the bundled sessions were simulated; see DrawImuTruth's bias).
Eigen::Vector3d NormalVector(std::normal_distribution<double>& normal, pcg64* rng) {
  const double z = normal(*rng);
  const double y = normal(*rng);
  const double x = normal(*rng);
  return {x, y, z};
}

void Sample(const SimulationOptions& o, const std::vector<Phase>& phases, pcg64* rng, Tag* tag,
            SimColumnsData* columns, SimulatedSession* out) {
  std::normal_distribution<double> normal(0.0, 1.0);
  double total_s = 0;
  for (const Phase& p : phases) total_s += p.duration_s;
  const double dt = 1.0 / o.rate_hz;
  const size_t n = static_cast<size_t>(std::floor(total_s * o.rate_hz));
  const double accel_sd_g = o.accel_noise_ug_rthz * 1e-6 * std::sqrt(o.bandwidth_hz);
  const double gyro_sd_dps = o.gyro_noise_dps_rthz * std::sqrt(o.bandwidth_hz);
  const double g_norm = o.gravity_mps2 / kStandardGravityMps2;

  SimColumnsData& cols = *columns;
  for (auto& c : cols) c.reserve(n);
  size_t phase = 0;
  double phase_start = 0;
  Eigen::Matrix3d prev = phases.front().At(0);
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    while (phase + 1 < phases.size() && t >= phase_start + phases[phase].duration_s) {
      phase_start += phases[phase].duration_s;
      ++phase;
    }
    const Eigen::Matrix3d r = phases[phase].At(t - phase_start);
    // Mean body rate over (t_{k-1}, t_k]: the rotation between the samples over dt.
    Eigen::Vector3d w_dps = Eigen::Vector3d::Zero();
    if (k > 0) {
      const Eigen::AngleAxisd step(prev.transpose() * r);
      w_dps = step.axis() * step.angle() / dt * 180.0 / kPi;
    }
    prev = r;
    const Eigen::Vector3d f_g = r.transpose() * Eigen::Vector3d::UnitZ() * g_norm;
    double temp_c = o.temp_start_c + (o.temp_end_c - o.temp_start_c) * t / total_s;
    temp_c = std::round(temp_c * 340.0) / 340.0;  // MPU6050: 340 LSB/degC.
    const Eigen::Vector3d na = NormalVector(normal, rng);
    const Eigen::Vector3d ng = NormalVector(normal, rng);
    bool sat = false;
    const Eigen::Vector3d ra = TruthToCounts(out->truth.accel, f_g + accel_sd_g * na, temp_c, &sat);
    const Eigen::Vector3d rg =
        TruthToCounts(out->truth.gyro, w_dps + gyro_sd_dps * ng, temp_c, &sat);
    out->saturated_samples += sat ? 1 : 0;
    tag->t_s.push_back(t);
    tag->line.push_back(static_cast<uint32_t>(k + 2));
    for (int a = 0; a < 3; ++a) {
      cols[a].push_back(ra[a]);
      cols[3 + a].push_back(rg[a]);
    }
    cols[6].push_back(temp_c);
    cols[7].push_back(phases[phase].TableRate());
    out->true_accel_g.push_back(f_g);
    out->true_gyro_dps.push_back(w_dps);
  }
}

// The session: its path, columns and the one tag, the columns o leaves out dropped.
void AssembleSession(const SimulationOptions& o, Tag tag, SimColumnsData* columns,
                     SimulatedSession* out) {
  SimColumnsData& cols = *columns;
  const size_t n = tag.t_s.size();
  const char* names[8] = {"ax_lsb", "ay_lsb", "az_lsb", "gx_lsb",
                          "gy_lsb", "gz_lsb", "temp_c", "table_rate_dps"};
  Session& s = out->session;
  s.path = fmt::format("simulated-seed-{}", o.seed);
  s.format = SessionFormat::kCsv;
  s.rows = static_cast<int64_t>(n);
  s.columns = {"t_s", "sensor"};
  for (int c = 0; c < 8; ++c) {
    if (c == 6 && !o.temperature) continue;
    if (c == 7 && o.table_rates_dps.empty() && !o.write_table_column) continue;
    Quantity q;
    q.name = names[c];
    q.unit = ClassifyColumn(names[c]).UnitSymbol();
    q.values = std::move(cols[c]);
    tag.quantities.push_back(std::move(q));
    s.columns.push_back(names[c]);
  }
  s.tags.push_back(std::move(tag));
}

}  // namespace

Eigen::Vector3d TruthToCounts(const SensorModel& truth, const Eigen::Vector3d& value, double temp_c,
                              bool* saturated) {
  Eigen::Vector3d raw = truth.Invert(value, temp_c);
  for (int a = 0; a < 3; ++a) {
    raw[a] = std::round(raw[a]);
    if (raw[a] <= -32768.0 || raw[a] >= 32767.0) *saturated = true;
    raw[a] = std::clamp(raw[a], -32768.0, 32767.0);
  }
  return raw;
}

Result<SimulatedSession> SimulateCalibrationSession(const SimulationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("invalid simulation options: " + why);
  SimulatedSession out;
  out.truth = o.random_truth ? DrawImuTruth(o.seed, o.accel_fs_g, o.gyro_fs_dps, o.temperature,
                                            o.accel_cross_axis, o.gyro_cross_axis)
                             : o.truth;
  if (o.temperature) {
    const double t_mid = 0.5 * (o.temp_start_c + o.temp_end_c);
    out.truth.accel.has_temperature = out.truth.gyro.has_temperature = true;
    out.truth.accel.t_ref_c = out.truth.gyro.t_ref_c = t_mid;
  }
  pcg64 rng(o.seed ^ 0x9e3779b97f4a7c15ULL);
  const std::vector<Phase> phases = Timeline(o, PoseGravityDirections(o), &rng);
  Tag tag;
  tag.sensor = o.sensor;
  SimColumnsData cols;
  Sample(o, phases, &rng, &tag, &cols, &out);
  AssembleSession(o, std::move(tag), &cols, &out);
  return out;
}

namespace {

nlohmann::ordered_json Vec(const Eigen::Vector3d& v) { return {v[0], v[1], v[2]}; }

nlohmann::ordered_json TruthSensorJson(const SensorModel& m) {
  using Json = nlohmann::ordered_json;
  const Eigen::Matrix3d matrix = m.Matrix();
  Json rows = Json::array();
  for (int r = 0; r < 3; ++r) rows.push_back({matrix(r, 0), matrix(r, 1), matrix(r, 2)});
  Json j = {{"model", ModelKindName(m.kind)},
            {"input_unit", m.input_unit},
            {"output_unit", m.output_unit},
            {"bias", Vec(m.bias)},
            {"scale", Vec(m.scale)},
            {"misalignment", m.misalignment},
            {"matrix", rows},
            {"sensitivity", Vec(m.scale.cwiseInverse())}};
  if (m.has_temperature) {
    j["temperature"] = {{"t_ref_c", m.t_ref_c}, {"bias_per_c", Vec(m.bias_per_c)}};
  }
  return j;
}

}  // namespace

std::string CalibrationTruthJson(const SimulationOptions& o, const SimulatedSession& sim) {
  using Json = nlohmann::ordered_json;
  Json j = {{"schema", "metro.calibration-truth/1"},
            {"model_equation",
             "calibrated = T K (raw - b0 - b1 (temp_c - t_ref_c)), bias removed before scaling "
             "(docs/calibration-model.md)"},
            {"seed", o.seed},
            {"sensor", o.sensor},
            {"rate_hz", o.rate_hz},
            {"poses", o.poses},
            {"dwell_s", o.dwell_s},
            {"move_s", o.move_s},
            {"table_rates_dps", o.table_rates_dps},
            {"table_run_s", o.table_run_s},
            {"accel_fs_g", o.accel_fs_g},
            {"gyro_fs_dps", o.gyro_fs_dps},
            {"gravity_mps2", o.gravity_mps2},
            {"accel_noise_ug_rthz", o.accel_noise_ug_rthz},
            {"gyro_noise_dps_rthz", o.gyro_noise_dps_rthz},
            {"bandwidth_hz", o.bandwidth_hz},
            {"rows", sim.session.rows},
            {"saturated_samples", sim.saturated_samples}};
  if (o.temperature) {
    j["temp_start_c"] = o.temp_start_c;
    j["temp_end_c"] = o.temp_end_c;
  }
  if (o.pose_tilt_deg > 0) j["pose_tilt_deg"] = o.pose_tilt_deg;
  j["accel"] = TruthSensorJson(sim.truth.accel);
  j["gyro"] = TruthSensorJson(sim.truth.gyro);
  return j.dump(2) + "\n";
}

}  // namespace metro
