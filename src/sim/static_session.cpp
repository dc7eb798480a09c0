// SimulateStaticSession runs these stages, in this order:
//
//   model     ModelOf                     sampling, AR(1) noise per step, columns
//   truth     Draws, DrawTruth            the generator; every tag's attitude, transient,
//                                         biases and starting noise, in sensor order
//   steps     DrawReading,                per step and tag: the drawn observation, written
//             AppendReceiverLine,         as a receiver line or a session.csv row (the same
//             AppendCsvRow                draws for both formats), flushed every 8 MiB
#include "metro/sim/static_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <pcg_random.hpp>
#include <random>
#include <string>

#include "metro/sim/limits.hpp"

namespace metro {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr size_t kFlushBytes = size_t{8} << 20;

struct TagState {
  StaticTagTruth truth;
  bool never = false;
  double noise[3] = {0, 0, 0};
  bool have_packet = false;
  ReceiverPayload last_payload{};
};

// Accelerometer reading of gravity for a tag at rest: R^T (0, 0, 1) in g, where R is the
// world-from-body rotation of the (1,2,3) Euler angles (it does not depend on yaw).
void GravityInBody(const EulerDeg& e, double out[3]) {
  const double cp = std::cos(e.pitch_deg * kRadPerDeg), sp = std::sin(e.pitch_deg * kRadPerDeg);
  const double cr = std::cos(e.roll_deg * kRadPerDeg), sr = std::sin(e.roll_deg * kRadPerDeg);
  // Third row of R = Rz(yaw) Ry(pitch) Rx(roll), i.e. the world z axis in body axes.
  out[0] = -sp;
  out[1] = cp * sr;
  out[2] = cp * cr;
}

double Quantize(double v, double step) { return step > 0 ? std::round(v / step) * step : v; }

int16_t ToInt16(double v) {
  return static_cast<int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
}

}  // namespace

bool StaticSimulationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (sensors.empty() && never_sensors.empty()) return fail("no sensors to simulate");
  for (int s : sensors) {
    if (s < 1 || s > 255) return fail(fmt::format("sensor {} is not in 1..255", s));
    if (std::count(sensors.begin(), sensors.end(), s) > 1) {
      return fail(fmt::format("sensor {} is listed twice", s));
    }
  }
  for (int s : never_sensors) {
    if (s < 1 || s > 255) return fail(fmt::format("sensor {} is not in 1..255", s));
    if (std::count(sensors.begin(), sensors.end(), s) > 0) {
      return fail(fmt::format("sensor {} cannot both send and never connect", s));
    }
  }
  if (!(duration_s > 0.0 && duration_s <= kSimMaxDurationS)) {
    return fail(
        fmt::format("duration_s must be in (0, {:g}] s, got {:g}", kSimMaxDurationS, duration_s));
  }
  if (std::string sampling; !SamplingWithinLimits(rate_hz, frame_period_s, &sampling)) {
    return fail(sampling);
  }
  const double per_s = rate_hz > 0.0 ? rate_hz : 1.0 / frame_period_s;
  const double observations =
      duration_s * per_s * static_cast<double>(sensors.size() + never_sensors.size());
  if (observations > kSimMaxObservations) {
    return fail(
        fmt::format("{:.3g} observations (duration x rate x tags) is more than the "
                    "simulator writes ({:g}); shorten the session or lower the rate",
                    observations, kSimMaxObservations));
  }
  if (!(noise_ar1 >= 0.0 && noise_ar1 < 1.0)) return fail("noise_ar1 must be in [0, 1)");
  if (!(packet_loss >= 0.0 && packet_loss < 1.0)) return fail("packet_loss must be in [0, 1)");
  if (!(transient_tau_s > 0.0)) return fail("transient_tau_s must be > 0");
  if (!(quantization_deg >= 0.0)) return fail("quantization_deg must be >= 0");
  return true;
}

namespace {

// ---- SimulateStaticSession's stages -------------------------------------------------------

// The sampling and noise the session is drawn with.
struct StaticModel {
  bool receiver = false;  // A receiver capture, else session.csv.
  double dt_s = 0, rate_hz = 0;
  double phi = 0, innovation = 0;  // AR(1) of the attitude noise per step.
  double accel_noise_g = 0, gyro_noise_dps = 0;
  bool angles = false, imu = false;  // Columns of session.csv.
};

StaticModel ModelOf(const StaticSimulationOptions& options, SessionFormat format) {
  StaticModel m;
  m.receiver = format == SessionFormat::kReceiver;
  m.dt_s = m.receiver || options.rate_hz == 0.0 ? options.frame_period_s : 1.0 / options.rate_hz;
  m.rate_hz = 1.0 / m.dt_s;
  m.phi = std::pow(options.noise_ar1, m.dt_s / options.frame_period_s);
  m.innovation = std::sqrt(1.0 - m.phi * m.phi);
  m.accel_noise_g = 400e-6 * std::sqrt(m.rate_hz / 2.0);
  m.gyro_noise_dps = 0.005 * std::sqrt(m.rate_hz / 2.0);
  m.angles = options.columns != SimColumns::kImu;
  m.imu = options.columns != SimColumns::kAngles;
  return m;
}

// The generator and its distributions, drawn in one fixed order.
struct Draws {
  explicit Draws(uint64_t seed) : rng(seed) {}
  pcg64 rng;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform;
  double Normal() { return normal(rng); }
  double Uniform() { return uniform(rng); }
};

// Every tag's truth, in sensor order.
std::vector<TagState> DrawTruth(const StaticSimulationOptions& options, Draws* draws) {
  std::vector<int> all = options.sensors;
  all.insert(all.end(), options.never_sensors.begin(), options.never_sensors.end());
  std::sort(all.begin(), all.end());
  std::vector<TagState> tags(all.size());
  for (size_t k = 0; k < all.size(); ++k) {
    TagState& s = tags[k];
    s.truth.sensor = all[k];
    s.never = std::count(options.never_sensors.begin(), options.never_sensors.end(), all[k]) > 0;
    // Sensor 2 (chest) lies flat as in thesis 8.4.2; the others at random attitudes.
    if (all[k] != 2) {
      s.truth.attitude = {360.0 * draws->Uniform() - 180.0, 60.0 * draws->Uniform() - 30.0,
                          60.0 * draws->Uniform() - 30.0};
    }
    s.truth.transient_offset = {options.transient_std_deg[0] * draws->Normal(),
                                options.transient_std_deg[1] * draws->Normal(),
                                options.transient_std_deg[2] * draws->Normal()};
    for (int a = 0; a < 3; ++a) {
      s.truth.accel_bias_g[a] = 0.02 * draws->Normal();
      s.truth.gyro_bias_dps[a] = 3.0 * draws->Normal();
      s.noise[a] = options.noise_std_deg[a] * draws->Normal();  // Stationary start.
    }
  }
  return tags;
}

// One observation of a tag at time t: its DMP angles e, accelerometer, gyroscope,
// temperature, quaternion and whether the packet is lost.
struct Reading {
  double e[3] = {0, 0, 0};
  double accel[3] = {0, 0, 0}, gyro[3] = {0, 0, 0};
  double temp_c = 0;
  bool lost = false;
  Quaternion q;
};

// Draw every random number for every step so the two formats share one truth.
Reading DrawReading(const StaticSimulationOptions& options, const StaticModel& m, double t,
                    double settle, TagState* tag, Draws* draws) {
  TagState& s = *tag;
  Reading r;
  double* e = r.e;
  const double phi = m.phi, innovation = m.innovation;
  for (int a = 0; a < 3; ++a) {
    s.noise[a] = phi * s.noise[a] + innovation * options.noise_std_deg[a] * draws->Normal();
  }
  const double attitude[3] = {s.truth.attitude.yaw_deg, s.truth.attitude.pitch_deg,
                              s.truth.attitude.roll_deg};
  const double offset[3] = {s.truth.transient_offset.yaw_deg, s.truth.transient_offset.pitch_deg,
                            s.truth.transient_offset.roll_deg};
  for (int a = 0; a < 3; ++a) {
    e[a] = attitude[a] + offset[a] * settle + s.noise[a];
    if (a == 0) e[a] = WrapDeg180(e[a] + options.yaw_drift_dps * t);
    e[a] = Quantize(e[a], options.quantization_deg);
  }
  const EulerDeg euler{e[0], e[1], e[2]};
  // The accelerometer sees the tag's physical (static) attitude, not the DMP's noise.
  double* accel = r.accel;
  double* gyro = r.gyro;
  GravityInBody(s.truth.attitude, accel);
  for (int a = 0; a < 3; ++a) {
    accel[a] += s.truth.accel_bias_g[a] + m.accel_noise_g * draws->Normal();
    gyro[a] = s.truth.gyro_bias_dps[a] + m.gyro_noise_dps * draws->Normal();
  }
  r.temp_c = Quantize(25.0 + 5.0 * (1.0 - std::exp(-t / 600.0)), 1.0 / 340.0);
  r.lost = draws->Uniform() < options.packet_loss;
  r.q = QuaternionFromEuler(euler);
  return r;
}

// A receiver line: fresh with the quaternion and packet #0 (yaw, pitch, roll, counter k),
// or, when lost, the last packet as stale (never, before the first).
void AppendReceiverLine(const Reading& r, int64_t k, TagState* tag, std::string* out) {
  TagState& s = *tag;
  const double* e = r.e;
  const Quaternion& q = r.q;
  if (r.lost) {
    *out += FormatReceiverLine(
        s.truth.sensor, s.have_packet ? NewDataFlag::kStale : NewDataFlag::kNever, s.last_payload);
  } else {
    ReceiverPayload p{};
    EncodeQuaternion(q, &p);
    // Bytes 17..25: packet type #0 with yaw, pitch, roll as int16 at 0.01 deg
    // (little-endian), then a 16-bit packet counter.
    p[16] = 0;
    const int16_t v[3] = {ToInt16(e[0] * 100.0), ToInt16(e[1] * 100.0), ToInt16(e[2] * 100.0)};
    for (int a = 0; a < 3; ++a) {
      p[17 + 2 * a] = static_cast<uint8_t>(static_cast<uint16_t>(v[a]) & 0xFF);
      p[18 + 2 * a] = static_cast<uint8_t>(static_cast<uint16_t>(v[a]) >> 8);
    }
    p[23] = static_cast<uint8_t>(k & 0xFF);
    p[24] = static_cast<uint8_t>((k >> 8) & 0xFF);
    s.last_payload = p;
    s.have_packet = true;
    *out += FormatReceiverLine(s.truth.sensor, NewDataFlag::kFresh, p);
  }
  *out += '\n';
}

// A session.csv row (nothing when the packet is lost).
void AppendCsvRow(const StaticModel& m, double t, int sensor, const Reading& r, std::string* out) {
  if (r.lost) return;
  auto it = std::back_inserter(*out);
  const Quaternion& q = r.q;
  const double* accel = r.accel;
  const double* gyro = r.gyro;
  fmt::format_to(it, "{:.6f},{}", t, sensor);
  if (m.angles) {
    fmt::format_to(it, ",{:.8f},{:.8f},{:.8f},{:.8f}", q.w, q.x, q.y, q.z);
  }
  if (m.imu) {
    fmt::format_to(it, ",{:.6f},{:.6f},{:.6f},{:.4f},{:.4f},{:.4f},{:.3f}", accel[0], accel[1],
                   accel[2], gyro[0], gyro[1], gyro[2], r.temp_c);
  }
  *out += '\n';
}

}  // namespace

Status SimulateStaticSession(const StaticSimulationOptions& options, SessionFormat format,
                             const TextSink& sink, std::vector<StaticTagTruth>* truth) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid simulation options: " + why);
  if (format != SessionFormat::kCsv && format != SessionFormat::kReceiver) {
    return MakeError("the simulator writes session.csv or receiver captures");
  }
  const StaticModel m = ModelOf(options, format);
  Draws draws(options.seed);
  std::vector<TagState> tags = DrawTruth(options, &draws);
  if (truth != nullptr) {
    truth->clear();
    for (const TagState& s : tags) truth->push_back(s.truth);
  }

  std::string out;
  out.reserve(kFlushBytes + 4096);
  auto it = std::back_inserter(out);
  if (!m.receiver) {
    out += "# metro simulate: static session, ";
    fmt::format_to(it, "seed {}, {} s at {:.6g} Hz\n", options.seed, options.duration_s, m.rate_hz);
    out += "t_s,sensor";
    if (m.angles) out += ",qw,qx,qy,qz";
    if (m.imu) out += ",ax_g,ay_g,az_g,gx_dps,gy_dps,gz_dps,temp_c";
    out += '\n';
  }
  const int64_t steps = static_cast<int64_t>(std::floor(options.duration_s / m.dt_s));
  for (int64_t k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * m.dt_s;
    const double settle = std::exp(-t / options.transient_tau_s);
    for (TagState& s : tags) {
      if (s.never) {
        if (m.receiver) {
          out += FormatReceiverLine(s.truth.sensor, NewDataFlag::kNever, ReceiverPayload{});
          out += '\n';
        }
        continue;
      }
      const Reading r = DrawReading(options, m, t, settle, &s, &draws);
      if (m.receiver) {
        AppendReceiverLine(r, k, &s, &out);
      } else {
        AppendCsvRow(m, t, s.truth.sensor, r, &out);
      }
    }
    if (out.size() >= kFlushBytes) {
      if (Status st = sink(out); !st.ok()) return st;
      out.clear();
    }
  }
  if (!out.empty()) return sink(out);
  return Status::Ok();
}

}  // namespace metro
