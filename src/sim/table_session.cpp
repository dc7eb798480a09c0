// SimulateTableSession runs these stages, in this order:
//
//   schedule   Schedule, FillTruth       the plateaus and their truth
//   tag log    WriteTagLog, TableTag     per step: the table's angle, the tag's lagged,
//                                        noisy, tilted angles and packet loss; session.csv
//                                        or a receiver capture
//   reference  WriteReferenceLog         the table's own log, when asked for
#include "metro/sim/table_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>
#include <pcg_random.hpp>
#include <random>
#include <string>

#include "metro/sim/limits.hpp"

namespace metro {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;
constexpr size_t kFlushBytes = size_t{8} << 20;

double Quantize(double v, double step) { return step > 0 ? std::round(v / step) * step : v; }

// One plateau of the schedule: the table moves from the previous angle during
// [t_move_s, t_arrive_s), then dwells until t_leave_s.
struct Stop {
  double angle_deg = 0.0;
  int direction = 0;
  double t_move_s = 0.0;
  double t_arrive_s = 0.0;
  double t_leave_s = 0.0;
};

std::vector<double> PlateauAngles(const TableSimulationOptions& o) {
  std::vector<double> up;
  const int steps = static_cast<int>(std::floor((o.end_deg - o.start_deg) / o.step_deg + 1e-9));
  for (int i = 0; i <= steps; ++i) up.push_back(o.start_deg + i * o.step_deg);
  std::vector<double> all;
  for (int s = 0; s < o.sweeps; ++s) {
    // Up pass (the start is not repeated after the first sweep's down pass), then down.
    for (size_t i = (s == 0 ? 0 : 1); i < up.size(); ++i) all.push_back(up[i]);
    if (o.up_only) break;
    for (size_t i = up.size() - 1; i-- > 0;) all.push_back(up[i]);
  }
  return all;
}

std::vector<Stop> Schedule(const TableSimulationOptions& o) {
  std::vector<Stop> stops;
  double t = 0.0;
  double previous = 0.0;
  for (double angle : PlateauAngles(o)) {
    Stop s;
    s.angle_deg = angle;
    s.t_move_s = t;
    if (!stops.empty()) {
      s.direction = angle > previous ? 1 : -1;
      t += std::fabs(angle - previous) / o.move_rate_dps;
    }
    // An up-only sweep approaches its first plateau from below too.
    if (o.up_only) s.direction = 1;
    s.t_arrive_s = t;
    t += o.dwell_s;
    s.t_leave_s = t;
    stops.push_back(s);
    previous = angle;
  }
  return stops;
}

// Table angle and the direction of its last move at time t_s (`hint` speeds up the search).
// During [t_move_s, t_arrive_s) of stop i > 0 the table turns at move_rate_dps from stop
// i - 1 towards stop i; from t_arrive_s to the next stop's t_move_s it rests at stop i.
double TableAngle(const std::vector<Stop>& stops, double t_s, size_t* hint, int* direction) {
  size_t& i = *hint;
  while (i + 1 < stops.size() && t_s >= stops[i + 1].t_move_s) ++i;
  const Stop& s = stops[i];
  *direction = s.direction;
  if (i > 0 && t_s < s.t_arrive_s) {
    const double frac = (t_s - s.t_move_s) / (s.t_arrive_s - s.t_move_s);
    return stops[i - 1].angle_deg + frac * (s.angle_deg - stops[i - 1].angle_deg);
  }
  return s.angle_deg;
}

// The table's readout of theta: its encoder resolution, wrapped into (-180, 180] when the
// table reports signed angles.
double Readout(const TableSimulationOptions& o, double theta_deg) {
  return Quantize(o.readout_wrap_180 ? WrapDeg180(theta_deg) : theta_deg,
                  o.reference_resolution_deg);
}

}  // namespace

bool TableSimulationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (sensor < 1 || sensor > 255) return fail(fmt::format("sensor {} is not in 1..255", sensor));
  if (!(step_deg >= kSimMinTableStepDeg) || !std::isfinite(step_deg)) {
    return fail(
        fmt::format("step_deg must be at least {:g} deg, got {:g}", kSimMinTableStepDeg, step_deg));
  }
  if (!(end_deg > start_deg) || !std::isfinite(start_deg) || !std::isfinite(end_deg)) {
    return fail("end_deg must be greater than start_deg");
  }
  if (end_deg - start_deg > 360.0) return fail("the sweep may span at most 360 deg");
  const double plateaus = std::floor((end_deg - start_deg) / step_deg) + 1.0;
  if (plateaus > kSimMaxTablePlateaus) {
    return fail(
        fmt::format("{:.0f} plateaus per sweep ((end - start) / step + 1) is more than "
                    "{}; take a larger step_deg",
                    plateaus, kSimMaxTablePlateaus));
  }
  if (sweeps < 1 || sweeps > 100) return fail("sweeps must be in 1..100");
  if (up_only && sweeps != 1) return fail("an up-only sweep is one pass: sweeps must be 1");
  if (!(dwell_s > 0.0) || !std::isfinite(dwell_s)) return fail("dwell_s must be > 0");
  if (!(move_rate_dps > 0.0) || !std::isfinite(move_rate_dps)) {
    return fail("move_rate_dps must be > 0");
  }
  if (std::string sampling; !SamplingWithinLimits(rate_hz, frame_period_s, &sampling)) {
    return fail(sampling);
  }
  // Up and down, each plateau's dwell and the moves between them.
  const double duration_s =
      2.0 * sweeps * (plateaus * dwell_s + (end_deg - start_deg) / move_rate_dps);
  if (duration_s > kSimMaxDurationS) {
    return fail(
        fmt::format("the sweeps last {:.3g} s, more than {:g} s; fewer plateaus, "
                    "sweeps or a shorter dwell_s",
                    duration_s, kSimMaxDurationS));
  }
  const double per_s = rate_hz > 0.0 ? rate_hz : 1.0 / frame_period_s;
  if (duration_s * std::max(per_s, reference_rate_hz) > kSimMaxObservations) {
    return fail(
        fmt::format("{:.3g} observations is more than the simulator writes ({:g}); "
                    "lower the rate or shorten the sweeps",
                    duration_s * std::max(per_s, reference_rate_hz), kSimMaxObservations));
  }
  if (!(noise_std_deg >= 0.0)) return fail("noise_std_deg must be >= 0");
  if (!(noise_ar1 >= 0.0 && noise_ar1 < 1.0)) return fail("noise_ar1 must be in [0, 1)");
  if (!(lag_tau_s >= 0.0)) return fail("lag_tau_s must be >= 0");
  if (!(quantization_deg >= 0.0)) return fail("quantization_deg must be >= 0");
  if (!(reference_resolution_deg >= 0.0)) return fail("reference_resolution_deg must be >= 0");
  if (!(packet_loss >= 0.0 && packet_loss < 1.0)) return fail("packet_loss must be in [0, 1)");
  if (!(reference_rate_hz > 0.0 && reference_rate_hz <= kSimMaxRateHz)) {
    return fail(fmt::format("reference_rate_hz must be in (0, {:g}] Hz", kSimMaxRateHz));
  }
  if (!std::isfinite(reference_clock_offset_s)) return fail("reference_clock_offset_s");
  for (double v : {offset_deg, scale_error, cos1_deg, sin1_deg, hysteresis_deg, tilt_deg,
                   base_deg[0], base_deg[1]}) {
    if (!std::isfinite(v)) return fail("the error model's parameters must be finite");
  }
  if (axis == TableAxis::kPitch && !pitch_through_90) {
    // Pitch is an Euler angle in [-90, 90]: the sweep must stay clear of gimbal lock.
    const double margin = std::fabs(offset_deg) + std::fabs(scale_error) * 90.0 +
                          std::hypot(cos1_deg, sin1_deg) + std::fabs(hysteresis_deg);
    if (std::fabs(start_deg) + margin > kGimbalLockWarnPitchDeg ||
        std::fabs(end_deg) + margin > kGimbalLockWarnPitchDeg) {
      return fail(fmt::format("a pitch table must stay within +-{} deg", kGimbalLockWarnPitchDeg));
    }
  } else {
    const double pitch_base = axis == TableAxis::kYaw ? base_deg[0] : base_deg[1];
    if (std::fabs(pitch_base) + std::fabs(tilt_deg) > kGimbalLockWarnPitchDeg) {
      return fail("the tag's pitch must stay clear of +-90 deg");
    }
  }
  return true;
}

double TableErrorModelDeg(const TableSimulationOptions& o, double theta_deg, int direction) {
  const double th = theta_deg * kRadPerDeg;
  return o.offset_deg + o.scale_error * theta_deg + o.cos1_deg * std::cos(th) +
         o.sin1_deg * std::sin(th) + 0.5 * direction * o.hysteresis_deg;
}

namespace {

// ---- SimulateTableSession's stages --------------------------------------------------------

// The plateaus as they are meant: reference, direction, error, times, the other angles.
void FillTruth(const TableSimulationOptions& options, const std::vector<Stop>& stops,
               TableTruth* truth) {
  const double duration_s = stops.back().t_leave_s;
  truth->plateaus.clear();
  for (const Stop& s : stops) {
    TablePlateauTruth p;
    p.reference_deg = s.angle_deg;
    p.direction = s.direction;
    p.error_deg = TableErrorModelDeg(options, s.angle_deg, s.direction);
    p.t_start_s = s.t_arrive_s;
    p.t_end_s = s.t_leave_s;
    p.t_move_s = s.t_move_s;
    const double th = s.angle_deg * kRadPerDeg;
    p.other_deg[0] = options.base_deg[0] + options.tilt_deg * std::sin(th);
    p.other_deg[1] = options.base_deg[1] + options.tilt_deg * std::cos(th);
    truth->plateaus.push_back(p);
  }
  truth->duration_s = duration_s;
}

// The tag on the table, step by step: its first-order lag behind the table's angle plus the
// error model, the AR(1) noise of its three angles, the tilt of the axes not turned, and
// packet loss. Draws from one generator in a fixed order (the noise's stationary start
// first, then per step three normals and one uniform).
class TableTag {
 public:
  TableTag(const TableSimulationOptions& options, double dt_s)
      : options_(options), rng_(options.seed) {
    phi_ = std::pow(options.noise_ar1, dt_s / options.frame_period_s);
    innovation_ = std::sqrt(1.0 - phi_ * phi_);
    lag_gain_ = options.lag_tau_s > 0.0 ? 1.0 - std::exp(-dt_s / options.lag_tau_s) : 1.0;
    turned_ = static_cast<int>(options.axis);
    for (int a = 0, j = 0; a < 3; ++a) {
      if (a != turned_) others_[j++] = a;
    }
    for (double& e : noise_) e = options.noise_std_deg * normal_(rng_);  // Stationary start.
  }

  // The tag's angles (yaw, pitch, roll) at step k, the table at theta moving in `direction`;
  // *lost when the step's packet is lost.
  void Step(int64_t k, double theta, int direction, double angles[3], bool* lost) {
    const double target = theta + TableErrorModelDeg(options_, theta, direction);
    lagged_ = k == 0 ? target : lagged_ + lag_gain_ * (target - lagged_);
    for (double& e : noise_) e = phi_ * e + innovation_ * options_.noise_std_deg * normal_(rng_);
    angles[turned_] = lagged_ + noise_[turned_];
    const double th = theta * kRadPerDeg;
    angles[others_[0]] =
        options_.base_deg[0] + options_.tilt_deg * std::sin(th) + noise_[others_[0]];
    angles[others_[1]] =
        options_.base_deg[1] + options_.tilt_deg * std::cos(th) + noise_[others_[1]];
    for (int a = 0; a < 3; ++a)
      angles[a] = Quantize(WrapDeg180(angles[a]), options_.quantization_deg);
    *lost = uniform_(rng_) < options_.packet_loss;
  }

 private:
  const TableSimulationOptions& options_;
  pcg64 rng_;
  std::normal_distribution<double> normal_;
  std::uniform_real_distribution<double> uniform_;
  double phi_ = 0, innovation_ = 0, lag_gain_ = 1;
  int turned_ = 0;
  int others_[2] = {0, 0};
  double noise_[3] = {0, 0, 0};
  double lagged_ = 0.0;
};

// The tag's log (session.csv, with the table column when there is no reference log, or a
// receiver capture), flushed to sink every 8 MiB.
Status WriteTagLog(const TableSimulationOptions& options, const std::vector<Stop>& stops,
                   double duration_s, bool receiver, bool with_reference, const TextSink& sink) {
  const double dt_s =
      receiver || options.rate_hz == 0.0 ? options.frame_period_s : 1.0 / options.rate_hz;
  TableTag tag(options, dt_s);
  std::string out;
  out.reserve(kFlushBytes + 4096);
  auto it = std::back_inserter(out);
  const bool table_column = !receiver && !with_reference;
  if (!receiver) {
    fmt::format_to(it,
                   "# metro simulate --kind table: {} axis, seed {}, {} sweep(s) {}..{} deg by "
                   "{} deg, {:.6g} s at {:.6g} Hz\n",
                   TableAxisName(options.axis), options.seed, options.sweeps, options.start_deg,
                   options.end_deg, options.step_deg, duration_s, 1.0 / dt_s);
    out += "t_s,sensor,qw,qx,qy,qz";
    if (table_column) out += ",table_angle_deg";
    out += '\n';
  }
  bool have_packet = false;
  ReceiverPayload last_payload{};
  size_t hint = 0;
  const int64_t steps = static_cast<int64_t>(std::floor(duration_s / dt_s)) + 1;
  for (int64_t k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * dt_s;
    int direction = 0;
    const double theta = TableAngle(stops, t, &hint, &direction);
    double angles[3];
    bool lost = false;
    tag.Step(k, theta, direction, angles, &lost);
    const Quaternion q = QuaternionFromEuler({angles[0], angles[1], angles[2]});
    if (receiver) {
      if (lost) {
        out += FormatReceiverLine(
            options.sensor, have_packet ? NewDataFlag::kStale : NewDataFlag::kNever, last_payload);
      } else {
        ReceiverPayload p{};
        EncodeQuaternion(q, &p);
        p[23] = static_cast<uint8_t>(k & 0xFF);
        p[24] = static_cast<uint8_t>((k >> 8) & 0xFF);
        last_payload = p;
        have_packet = true;
        out += FormatReceiverLine(options.sensor, NewDataFlag::kFresh, p);
      }
      out += '\n';
    } else if (!lost) {
      fmt::format_to(it, "{:.6f},{},{:.8f},{:.8f},{:.8f},{:.8f}", t, options.sensor, q.w, q.x, q.y,
                     q.z);
      if (table_column) {
        fmt::format_to(it, ",{:.6f}", Readout(options, theta));
      }
      out += '\n';
    }
    if (out.size() >= kFlushBytes) {
      if (Status st = sink(out); !st.ok()) return st;
      out.clear();
    }
  }
  if (!out.empty()) {
    if (Status st = sink(out); !st.ok()) return st;
  }
  return Status::Ok();
}

// The reference log: the table's readout at reference_rate_hz on its own clock.
Status WriteReferenceLog(const TableSimulationOptions& options, const std::vector<Stop>& stops,
                         double duration_s, const TextSink& reference_sink) {
  size_t hint = 0;
  std::string ref;
  auto rit = std::back_inserter(ref);
  fmt::format_to(rit,
                 "# metro simulate --kind table: reference log, {:.6g} Hz, clock offset {} s\n"
                 "t_s,table_angle_deg\n",
                 options.reference_rate_hz, options.reference_clock_offset_s);
  const int64_t ref_steps =
      static_cast<int64_t>(std::floor(duration_s * options.reference_rate_hz)) + 1;
  for (int64_t k = 0; k < ref_steps; ++k) {
    const double t = static_cast<double>(k) / options.reference_rate_hz;
    int direction = 0;
    const double theta = TableAngle(stops, t, &hint, &direction);
    fmt::format_to(rit, "{:.6f},{:.6f}\n", t + options.reference_clock_offset_s,
                   Readout(options, theta));
  }
  return reference_sink(ref);
}

}  // namespace

Status SimulateTableSession(const TableSimulationOptions& options, SessionFormat format,
                            const TextSink& sink, const TextSink& reference_sink,
                            TableTruth* truth) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid table simulation options: " + why);
  if (format != SessionFormat::kCsv && format != SessionFormat::kReceiver) {
    return MakeError("the simulator writes session.csv or receiver captures");
  }
  const bool receiver = format == SessionFormat::kReceiver;
  if (receiver && !reference_sink) {
    return MakeError("a receiver capture has no table column: give a reference log to write");
  }
  const std::vector<Stop> stops = Schedule(options);
  const double duration_s = stops.back().t_leave_s;
  if (truth != nullptr) FillTruth(options, stops, truth);
  if (Status s = WriteTagLog(options, stops, duration_s, receiver, bool(reference_sink), sink);
      !s.ok()) {
    return s;
  }
  if (!reference_sink) return Status::Ok();
  return WriteReferenceLog(options, stops, duration_s, reference_sink);
}

std::string TableTruthJson(const TableSimulationOptions& o, const TableTruth& truth) {
  using Json = nlohmann::ordered_json;
  Json plateaus = Json::array();
  for (const TablePlateauTruth& p : truth.plateaus) {
    plateaus.push_back({{"reference_deg", p.reference_deg},
                        {"direction", p.direction > 0   ? "up"
                                      : p.direction < 0 ? "down"
                                                        : "first"},
                        {"error_deg", p.error_deg},
                        {"t_move_s", p.t_move_s},
                        {"t_start_s", p.t_start_s},
                        {"t_end_s", p.t_end_s},
                        {"other_axes_deg", {p.other_deg[0], p.other_deg[1]}}});
  }
  const int turned = static_cast<int>(o.axis);
  Json others = Json::array();
  for (int a = 0; a < 3; ++a) {
    if (a != turned) others.push_back(TableAxisQuantity(static_cast<TableAxis>(a)));
  }
  Json j = {{"schema", "metro.table-truth/1"},
            {"seed", o.seed},
            {"sensor", o.sensor},
            {"table_axis", TableAxisName(o.axis)},
            {"quantity", TableAxisQuantity(o.axis)},
            {"error_model",
             "e(theta, d) = offset_deg + scale_error theta + cos1_deg cos(theta) + sin1_deg "
             "sin(theta) + d hysteresis_deg / 2, d = +1 up, -1 down, 0 first"},
            {"offset_deg", o.offset_deg},
            {"scale_error", o.scale_error},
            {"cos1_deg", o.cos1_deg},
            {"sin1_deg", o.sin1_deg},
            {"hysteresis_deg", o.hysteresis_deg},
            {"tilt_deg", o.tilt_deg},
            {"other_axes", others},
            {"other_axes_base_deg", {o.base_deg[0], o.base_deg[1]}},
            {"lag_tau_s", o.lag_tau_s},
            {"noise_std_deg", o.noise_std_deg},
            {"noise_ar1_per_frame", o.noise_ar1},
            {"frame_period_s", o.frame_period_s},
            {"quantization_deg", o.quantization_deg},
            {"reference_resolution_deg", o.reference_resolution_deg},
            {"readout_wrap_180", o.readout_wrap_180},
            {"up_only", o.up_only},
            {"reference_clock_offset_s", o.reference_clock_offset_s},
            {"table_rate_dps", o.move_rate_dps},
            {"dwell_s", o.dwell_s},
            {"packet_loss", o.packet_loss},
            {"duration_s", truth.duration_s},
            {"plateaus", plateaus}};
  return j.dump(2) + "\n";
}

}  // namespace metro
