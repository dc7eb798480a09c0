#include "metro/station/station.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <set>

#include "metro/calibration/named_constants.hpp"
#include "metro/core/check.hpp"

namespace metro::station {

namespace {

constexpr int kAxes = 6;  // ax ay az gx gy gz

// One record of the stream: the samples between two gaps.
struct Record {
  std::vector<double> t_s;
  std::vector<uint32_t> line;
  std::vector<std::array<int32_t, kAxes>> counts;
  std::vector<unsigned char> saturated;
  // Window variances (accelerometer, gyroscope) [LSB^2] of the window ending at each sample.
  std::vector<float> va, vg;
  std::optional<double> last_t_ms;
};

struct AcceptedPose {
  int record = 0;
  size_t begin = 0, end = 0;  // Samples [begin, end] of the record (inclusive).
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  std::string name;
};

// Sum over a sensor's axes of the variance of the last `width` samples.
class WindowVariance {
 public:
  explicit WindowVariance(size_t width) : width_(width) {}
  void Push(const std::array<int32_t, kAxes>& c) {
    window_.push_back(c);
    for (int a = 0; a < kAxes; ++a) {
      sum_[a] += c[a];
      sq_[a] += static_cast<double>(c[a]) * c[a];
    }
    if (window_.size() > width_) {
      const auto& old = window_.front();
      for (int a = 0; a < kAxes; ++a) {
        sum_[a] -= old[a];
        sq_[a] -= static_cast<double>(old[a]) * old[a];
      }
      window_.pop_front();
    }
  }
  bool Full() const { return window_.size() == width_; }
  // Sensor 0: accelerometer, 1: gyroscope.
  double Variance(int sensor) const {
    const double n = static_cast<double>(window_.size());
    double v = 0;
    for (int a = 3 * sensor; a < 3 * sensor + 3; ++a) {
      v += std::max(0.0, (sq_[a] - sum_[a] * sum_[a] / n) / (n - 1));
    }
    return v;
  }
  Eigen::Vector3d GyroMean() const {
    const double n = static_cast<double>(window_.size());
    return Eigen::Vector3d(sum_[3], sum_[4], sum_[5]) / n;
  }
  Eigen::Vector3d AccelMean() const {
    const double n = static_cast<double>(window_.size());
    return Eigen::Vector3d(sum_[0], sum_[1], sum_[2]) / n;
  }
  void Clear() {
    window_.clear();
    sum_.fill(0);
    sq_.fill(0);
  }

 private:
  size_t width_;
  std::deque<std::array<int32_t, kAxes>> window_;
  std::array<double, kAxes> sum_{}, sq_{};
};

// The noise floor of each sensor: the 20th percentile of the record's non-overlapping window
// variances (a calibration record is mostly still), the smallest before 5 windows.
class NoiseFloor {
 public:
  void Add(double accel, double gyro) {
    accel_.push_back(accel);
    gyro_.push_back(gyro);
  }
  bool Empty() const { return accel_.empty(); }
  double Accel() const { return Percentile(accel_); }
  double Gyro() const { return Percentile(gyro_); }
  void Clear() {
    accel_.clear();
    gyro_.clear();
  }

 private:
  static double Percentile(std::vector<double> v) {
    if (v.size() < 5) return *std::min_element(v.begin(), v.end());
    const size_t k = v.size() / 5;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }
  std::vector<double> accel_, gyro_;
};

enum class Mode { kMoving, kHolding, kTooClose };

double Nominal(ImuSensor s, const StationOptions& o) {
  return NominalScale(s, "LSB", s == ImuSensor::kAccel ? o.accel_fs_g : o.gyro_fs_dps).value();
}

}  // namespace

// ---- options, names ------------------------------------------------------------------------

bool StationOptions::IsValid(std::string* why) const {
  auto fail = [why](const std::string& m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (sensor < 1) return fail("--sensor must be >= 1");
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) return fail("--rate-hz must be > 0");
  if (!(accel_fs_g > 0) || !(gyro_fs_dps > 0)) return fail("full-scale settings must be > 0");
  if (!(target_u_accel_mg > 0) || !(target_u_gyro_dps > 0) || !(gyro_reference_dps > 0)) {
    return fail("--target-u-accel-mg, --target-u-gyro-dps and the reference rate must be > 0");
  }
  if (!(window_s > 0) || window_s * rate_hz < 5) {
    return fail(fmt::format("the stillness window ({} s) must hold at least 5 samples at {} Hz",
                            window_s, rate_hz));
  }
  if (!(still_factor > 1)) return fail("still_factor must be > 1");
  if (!(min_dwell_s > 0) || !(max_dwell_s >= min_dwell_s)) {
    return fail("min_dwell_s must be > 0 and max_dwell_s >= min_dwell_s");
  }
  if (!(dwell_fraction > 0 && dwell_fraction <= 1)) return fail("dwell_fraction: 0 < f <= 1");
  if (!(min_separation_deg > 0 && min_separation_deg < 90)) {
    return fail("min_separation_deg must be within 0 .. 90");
  }
  if (!(gap_factor > 1)) return fail("gap_factor must be > 1");
  if (!calibration.fit_accel) return fail("the station calibrates the accelerometer");
  return true;
}

const char* StationEventKindName(StationEventKind kind) {
  switch (kind) {
    case StationEventKind::kHoldStarted:
      return "hold_started";
    case StationEventKind::kHoldComplete:
      return "hold_complete";
    case StationEventKind::kPoseAccepted:
      return "pose_accepted";
    case StationEventKind::kPoseRejected:
      return "pose_rejected";
    case StationEventKind::kTooClose:
      return "too_close";
    case StationEventKind::kUncertainty:
      return "uncertainty";
    case StationEventKind::kTargetMet:
      return "target_met";
    case StationEventKind::kGap:
      return "gap";
    case StationEventKind::kStopped:
      return "stopped";
  }
  return "unknown";
}

int MinOrientations(ModelKind accel_model) {
  switch (accel_model) {
    case ModelKind::kBias:
      return 4;
    case ModelKind::kScale:
      return 7;
    case ModelKind::kFull:
      return 10;
  }
  return 10;
}

std::vector<ConstantU> ConstantUncertainties(const TagCalibration& tag, const StationOptions& o) {
  std::vector<ConstantU> out;
  for (const NamedConstant& c : NamedConstants(tag)) {
    const bool accel = c.name.rfind("accel.", 0) == 0;
    const SensorCalibration* s = accel ? &*tag.accel : &*tag.gyro;
    const std::string p = c.name.substr(c.name.find('.') + 1);
    if (p.rfind("b1_", 0) == 0 || c.covariance_index < 0) continue;  // Held or thermal.
    const int axis = p.size() == 3 && (p[0] == 'b' || p[0] == 'k') ? p[2] - 'x' : -1;
    const double full = accel ? 1000.0 : o.gyro_reference_dps;  // mg at 1 g; deg/s at ref.
    ConstantU u;
    u.name = c.name;
    u.unit = accel ? "mg" : "deg/s";
    u.target = accel ? o.target_u_accel_mg : o.target_u_gyro_dps;
    if (p[0] == 'b') {
      u.u = c.u * std::abs(s->model.scale[axis]) * (accel ? 1000.0 : 1.0);
    } else if (p[0] == 'k') {
      u.u = c.u / std::abs(s->model.scale[axis]) * full;
    } else {
      u.u = c.u * full;
    }
    u.met = u.u <= u.target;
    out.push_back(u);
  }
  return out;
}

namespace {

// Per-axis noise of a hold's mean, squared, times n: s^2 (1 + rho) / (1 - rho), in `scale`
// units (JCGM 100:2008 4.2.3; AR(1) effective n as SegmentMeanNoise in the calibration).
double MaxAxisLongRunVariance(const std::vector<Eigen::Vector3d>& v, double scale) {
  const size_t n = v.size();
  if (n < 3) return 0;
  double worst = 0;
  for (int a = 0; a < 3; ++a) {
    double mean = 0;
    for (const auto& x : v) mean += x[a];
    mean /= static_cast<double>(n);
    double c0 = 0, c1 = 0;
    for (size_t i = 0; i < n; ++i) {
      c0 += (v[i][a] - mean) * (v[i][a] - mean);
      if (i + 1 < n) c1 += (v[i][a] - mean) * (v[i + 1][a] - mean);
    }
    if (!(c0 > 0)) continue;
    const double rho = std::clamp(c1 / c0, 0.0, 0.9);
    const double var = c0 / static_cast<double>(n - 1) * scale * scale;
    worst = std::max(worst, var * (1 + rho) / (1 - rho));
  }
  return worst;
}

}  // namespace

int64_t DwellNeeded(const std::vector<Eigen::Vector3d>& accel,
                    const std::vector<Eigen::Vector3d>& gyro, const StationOptions& o) {
  const double goal_a_g = o.dwell_fraction * o.target_u_accel_mg * 1e-3;
  const double goal_g_dps = o.dwell_fraction * o.target_u_gyro_dps;
  const double va = MaxAxisLongRunVariance(accel, Nominal(ImuSensor::kAccel, o));
  const double vg = MaxAxisLongRunVariance(gyro, Nominal(ImuSensor::kGyro, o));
  const double n = std::max(va / (goal_a_g * goal_a_g), vg / (goal_g_dps * goal_g_dps));
  const double lo = o.min_dwell_s * o.rate_hz, hi = o.max_dwell_s * o.rate_hz;
  return static_cast<int64_t>(std::ceil(std::clamp(n, lo, hi)));
}

// ---- the station ---------------------------------------------------------------------------

struct Station::Impl {
  StationOptions o;
  std::string source;
  std::vector<ProtocolPose> poses;
  std::vector<Record> records{1};
  std::vector<AcceptedPose> accepted;
  size_t width;
  WindowVariance window;
  NoiseFloor floor;
  size_t since_floor = 0;
  Mode mode = Mode::kMoving;
  size_t hold_begin = 0;
  // The last saturated sample of the current record (index, axis, line); -1 when none.
  int64_t saturated_index = -1;
  std::string saturated_axis;
  int64_t saturated_line = 0;
  // Gyroscope means of the accepted poses [LSB]: their median is the bias that tells a steady
  // turn about the vertical (accelerometer still, gyroscope steady) from a pose.
  std::vector<Eigen::Vector3d> pose_gyro;
  bool hold_complete = false;
  int64_t dwell_needed = 0;
  std::string hold_name;
  Eigen::Vector3d hold_up = Eigen::Vector3d::UnitZ();
  std::optional<Eigen::Vector3d> last_rejected_up;
  double stillness = 0;
  double threshold_accel = 0, threshold_gyro = 0;
  Eigen::Vector3d current_up = Eigen::Vector3d::UnitZ();
  std::vector<ConstantU> u;
  std::string u_status = "no pose yet";
  std::set<std::string> met;
  bool done = false, targets_met = false;
  std::string stop_reason;
  int64_t samples = 0;

  Impl(StationOptions options, std::string src)
      : o(std::move(options)),
        source(std::move(src)),
        poses(ProtocolPoses(o.protocol)),
        width(static_cast<size_t>(std::lround(o.window_s * o.rate_hz))),
        window(width) {}

  Record& Current() { return records.back(); }
  std::vector<Eigen::Vector3d> TakenUps() const {
    std::vector<Eigen::Vector3d> t;
    for (const AcceptedPose& p : accepted) t.push_back(p.up);
    return t;
  }
  std::string NearestPoseName(const Eigen::Vector3d& up) const {
    int best = 0;
    for (size_t i = 1; i < poses.size(); ++i) {
      if (AngleDeg(poses[i].up_body, up) < AngleDeg(poses[best].up_body, up)) {
        best = static_cast<int>(i);
      }
    }
    const double d = AngleDeg(poses[best].up_body, up);
    return d < 10 ? poses[best].name : fmt::format("{} {:+.0f} deg", poses[best].name, d);
  }
  int NextPose() const {
    return ChooseNextPose(o.protocol, poses, TakenUps(), o.min_separation_deg);
  }
  // The floor falls as the record learns its noise (its first windows may all be motion): a hold
  // begins after the last window within it that the current thresholds call moving.
  void TrimHoldStart(size_t k) {
    const Record& r = records.back();
    for (size_t j = k; j >= hold_begin + width - 1 && j > 0; --j) {
      if (r.va[j] > threshold_accel || r.vg[j] > threshold_gyro) {
        hold_begin = j + 1;
        return;
      }
    }
  }
  // A saturated sample among the hold's samples up to k.
  bool HoldSaturated(size_t k) const {
    return saturated_index >= static_cast<int64_t>(hold_begin) &&
           saturated_index <= static_cast<int64_t>(k);
  }
  // A window whose gyroscope mean is off the bias (the median of the accepted poses') by more
  // than the calibration's steady-rotation limit (SegmentationOptions::max_static_rate_dps) is
  // a turn, however steady.
  bool SteadyTurn() const {
    if (pose_gyro.empty()) return false;
    Eigen::Vector3d bias;
    for (int a = 0; a < 3; ++a) {
      std::vector<double> v;
      for (const Eigen::Vector3d& g : pose_gyro) v.push_back(g[a]);
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      bias[a] = v[v.size() / 2];
    }
    const double limit_lsb = SegmentationOptions().max_static_rate_dps /
                             NominalScale(ImuSensor::kGyro, "LSB", o.gyro_fs_dps).value();
    return (window.GyroMean() - bias).norm() > limit_lsb;
  }
  // The pose to take after the current hold, as if it were accepted.
  std::string ChooseNextPoseAfter() const {
    std::vector<Eigen::Vector3d> taken = TakenUps();
    taken.push_back(hold_up);
    const int i = ChooseNextPose(o.protocol, poses, taken, o.min_separation_deg);
    return i < 0 ? std::string() : poses[static_cast<size_t>(i)].name;
  }
  std::string NextPoseName() const {
    const int i = NextPose();
    return i < 0 ? std::string() : poses[static_cast<size_t>(i)].name;
  }
  StationEvent Event(StationEventKind kind, int64_t line) const {
    StationEvent e;
    e.kind = kind;
    e.line = line;
    e.t_s = records.back().t_s.empty() ? 0 : records.back().t_s.back();
    return e;
  }

  bool AppendSample(const RawSample& s, int64_t line, std::vector<StationEvent>* events);
  void UpdateStillness(std::vector<StationEvent>* events, int64_t line);
  void StartHold(int64_t line, std::vector<StationEvent>* events);
  void ContinueHold(int64_t line, std::vector<StationEvent>* events);
  void EndHold(size_t last_still, int64_t line, std::vector<StationEvent>* events);
  void LiveUncertainty(int64_t line, std::vector<StationEvent>* events);
  void DecideStop(int64_t line, std::vector<StationEvent>* events);
  void Stop(bool met, const std::string& why, int64_t line, std::vector<StationEvent>* events);
  void StartRecord();
  std::vector<Session> Sessions() const;
  std::vector<AnnotatedSegment> Segments() const;
  CalibrationOptions FitOptions() const;
};

void Station::Impl::StartRecord() {
  if (!Current().t_s.empty()) records.emplace_back();
  window.Clear();
  floor.Clear();
  since_floor = 0;
  mode = Mode::kMoving;
  saturated_index = -1;
}

bool Station::Impl::AppendSample(const RawSample& s, int64_t line,
                                 std::vector<StationEvent>* events) {
  Record& r = Current();
  if (s.t_ms && r.last_t_ms && (*s.t_ms - *r.last_t_ms) * 1e-3 > o.gap_factor / o.rate_hz) {
    StationEvent e = Event(StationEventKind::kGap, line);
    e.reason = fmt::format("the tag's clock jumped by {:.0f} ms (samples lost): a new record",
                           *s.t_ms - *r.last_t_ms);
    if (mode == Mode::kHolding) e.reason += "; the hold in progress is dropped";
    events->push_back(e);
    StartRecord();
  }
  Record& cur = Current();
  const double t = static_cast<double>(cur.t_s.size()) / o.rate_hz;
  cur.t_s.push_back(t);
  cur.line.push_back(static_cast<uint32_t>(line));
  std::array<int32_t, kAxes> c{};
  for (int a = 0; a < 3; ++a) {
    c[a] = s.accel_lsb[a];
    c[3 + a] = s.gyro_lsb[a];
  }
  cur.counts.push_back(c);
  cur.saturated.push_back(s.saturated ? 1 : 0);
  cur.va.push_back(0.0f);
  cur.vg.push_back(0.0f);
  cur.last_t_ms = s.t_ms;
  window.Push(c);
  ++samples;
  if (s.saturated) {
    saturated_index = static_cast<int64_t>(cur.t_s.size()) - 1;
    saturated_axis = s.saturated_axis;
    saturated_line = line;
  }
  return window.Full();
}

void Station::Impl::UpdateStillness(std::vector<StationEvent>* events, int64_t line) {
  const double va = window.Variance(0), vg = window.Variance(1);
  if (++since_floor >= width || floor.Empty()) {
    floor.Add(va, vg);
    since_floor = 0;
  }
  threshold_accel = o.still_factor * std::max(floor.Accel(), 1.0);
  threshold_gyro = o.still_factor * std::max(floor.Gyro(), 1.0);
  stillness = std::max(va / threshold_accel, vg / threshold_gyro);
  Current().va.back() = static_cast<float>(va);
  Current().vg.back() = static_cast<float>(vg);
  current_up = window.AccelMean().normalized();
  const bool still = stillness < 1.0 && !SteadyTurn();
  const size_t k = Current().t_s.size() - 1;
  if (mode == Mode::kMoving && still) {
    StartHold(line, events);
  } else if (mode == Mode::kHolding && still) {
    ContinueHold(line, events);
  } else if (mode == Mode::kHolding) {
    EndHold(k >= width ? k - width : 0, line, events);
  } else if (mode == Mode::kTooClose && !still) {
    mode = Mode::kMoving;
  }
}

void Station::Impl::StartHold(int64_t line, std::vector<StationEvent>* events) {
  const size_t k = Current().t_s.size() - 1;
  hold_up = current_up;
  hold_name = NearestPoseName(hold_up);
  const int near = NearestWithin(TakenUps(), hold_up, o.min_separation_deg);
  if (near >= 0) {
    mode = Mode::kTooClose;
    StationEvent e = Event(StationEventKind::kTooClose, line);
    e.pose = near + 1;
    e.pose_name = hold_name;
    const std::string next = NextPoseName();
    e.reason = fmt::format("{:.0f} deg from pose {} ({}), closer than {:.0f} deg: not used{}",
                           AngleDeg(accepted[static_cast<size_t>(near)].up, hold_up), near + 1,
                           accepted[static_cast<size_t>(near)].name, o.min_separation_deg,
                           next.empty() ? "" : "; take " + next);
    events->push_back(e);
    return;
  }
  mode = Mode::kHolding;
  hold_begin = k + 1 - width;
  hold_complete = false;
  dwell_needed = static_cast<int64_t>(std::ceil(o.min_dwell_s * o.rate_hz));
  StationEvent e = Event(StationEventKind::kHoldStarted, line);
  e.pose_name = hold_name;
  const bool repeat = last_rejected_up && AngleDeg(*last_rejected_up, hold_up) < o.same_pose_deg;
  e.reason = repeat ? "the rejected pose again" : "";
  events->push_back(e);
}

void Station::Impl::ContinueHold(int64_t line, std::vector<StationEvent>* events) {
  const size_t k = Current().t_s.size() - 1;
  if (k % width == 0) TrimHoldStart(k);
  if (k < hold_begin + width) return;
  const size_t usable = k - width - hold_begin + 1;
  // The dwell from the hold's own noise, every window (and once it first can be measured).
  if (usable >= width && k % width == 0) {
    std::vector<Eigen::Vector3d> a, g;
    for (size_t i = hold_begin; i < hold_begin + usable; ++i) {
      const auto& c = Current().counts[i];
      a.emplace_back(c[0], c[1], c[2]);
      g.emplace_back(c[3], c[4], c[5]);
    }
    dwell_needed = DwellNeeded(a, g, o);
  }
  if (!hold_complete && !HoldSaturated(k) && static_cast<int64_t>(usable) >= dwell_needed &&
      usable >= 2 * width) {
    hold_complete = true;
    StationEvent e = Event(StationEventKind::kHoldComplete, line);
    e.pose_name = hold_name;
    const std::string next = ChooseNextPoseAfter();
    e.reason = next.empty() ? "hold complete" : "hold complete; next: " + next;
    events->push_back(e);
  }
}

void Station::Impl::EndHold(size_t last_still, int64_t line, std::vector<StationEvent>* events) {
  mode = Mode::kMoving;
  TrimHoldStart(std::min(last_still + width - 1, Current().t_s.size() - 1));
  const size_t n = last_still + 1 > hold_begin ? last_still + 1 - hold_begin : 0;
  const double held_s = static_cast<double>(n) / o.rate_hz;
  const double need_s = static_cast<double>(dwell_needed) / o.rate_hz;
  const bool saturated = HoldSaturated(Current().t_s.size() - 1);
  if (!saturated && n < 2 * width) return;  // Too short to be a pose attempt: no event.
  if (saturated || static_cast<int64_t>(n) < dwell_needed || n < 2 * width) {
    StationEvent e = Event(StationEventKind::kPoseRejected, line);
    e.pose_name = hold_name;
    if (saturated) {
      e.reason = fmt::format(
          "saturated: {} at the int16 limit (line {}); the pose is unusable, hold {} again "
          "without touching the tag (a saturated reading is a clipped one, not a measurement)",
          saturated_axis, saturated_line, hold_name);
    } else {
      e.reason = fmt::format(
          "disturbed after {:.1f} s of the {:.1f} s its noise needs (a knock, or moved too "
          "early): hold {} again; nothing of it is averaged in",
          held_s, need_s, hold_name);
    }
    last_rejected_up = hold_up;
    events->push_back(e);
    return;
  }
  AcceptedPose p;
  p.record = static_cast<int>(records.size()) - 1;
  p.begin = hold_begin;
  p.end = last_still;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), gyro = Eigen::Vector3d::Zero();
  for (size_t i = p.begin; i <= p.end; ++i) {
    const auto& c = Current().counts[i];
    mean += Eigen::Vector3d(c[0], c[1], c[2]);
    gyro += Eigen::Vector3d(c[3], c[4], c[5]);
  }
  p.up = mean.normalized();
  pose_gyro.push_back(gyro / static_cast<double>(n));
  p.name = hold_name;
  accepted.push_back(p);
  last_rejected_up.reset();
  StationEvent e = Event(StationEventKind::kPoseAccepted, line);
  e.pose = static_cast<int>(accepted.size());
  e.pose_name = p.name;
  const std::string next = NextPoseName();
  e.reason = fmt::format("{:.1f} s held (needed {:.1f} s){}", held_s, need_s,
                         next.empty() ? "" : "; next: " + next);
  events->push_back(e);
  LiveUncertainty(line, events);
  DecideStop(line, events);
}

void Station::Impl::LiveUncertainty(int64_t line, std::vector<StationEvent>* events) {
  StationEvent e = Event(StationEventKind::kUncertainty, line);
  e.pose = static_cast<int>(accepted.size());
  const int need = MinOrientations(o.calibration.accel_model);
  if (static_cast<int>(accepted.size()) < need) {
    u.clear();
    u_status = fmt::format(
        "needs {} more distinct orientation{} for the {} accelerometer model (its constants + "
        "1)",
        need - static_cast<int>(accepted.size()), need - accepted.size() == 1 ? "" : "s",
        ModelKindName(o.calibration.accel_model));
    e.reason = u_status;
    events->push_back(e);
    return;
  }
  const std::vector<Session> sessions = Sessions();
  std::vector<const Tag*> tags;
  for (const Session& s : sessions) tags.push_back(&s.tags.front());
  CalibrationOptions fit = FitOptions();
  fit.compare_models = false;
  Result<TagCalibration> r = CalibrateTag(tags, fit);
  if (!r.ok()) {
    u.clear();
    u_status = "not determined yet: " + r.error().message;
    e.reason = u_status;
    events->push_back(e);
    return;
  }
  u = ConstantUncertainties(r.value(), o);
  u_status.clear();
  e.u = u;
  events->push_back(e);
  for (const ConstantU& c : u) {
    if (!c.met || met.count(c.name) > 0) continue;
    met.insert(c.name);
    StationEvent m = Event(StationEventKind::kTargetMet, line);
    m.pose = static_cast<int>(accepted.size());
    m.u = {c};
    events->push_back(m);
  }
}

void Station::Impl::DecideStop(int64_t line, std::vector<StationEvent>* events) {
  const bool all_met =
      !u.empty() && std::all_of(u.begin(), u.end(), [](const ConstantU& c) { return c.met; });
  if (all_met) {
    Stop(true, fmt::format("every target met after {} poses", accepted.size()), line, events);
    return;
  }
  if (NextPose() >= 0) return;
  std::string why = fmt::format("the {} protocol is complete ({} poses) and ",
                                ProtocolName(o.protocol), accepted.size());
  if (u.empty()) {
    why += "the calibration is " + u_status;
  } else {
    why += "targets are not met:";
    for (const ConstantU& c : u) {
      if (c.met) continue;
      // u falls as 1/sqrt(poses) at this noise (more poses, or longer holds alike).
      const double factor = (c.u / c.target) * (c.u / c.target);
      why += fmt::format(
          " {} u {:.3g} {} > target {:.3g} {} (about {:.0f} poses, or holds {:.1f}x longer, "
          "would reach it);",
          c.name, c.u, c.unit, c.target, c.unit,
          std::ceil(factor * static_cast<double>(accepted.size())), factor);
    }
    why.pop_back();
  }
  Stop(false, why, line, events);
}

void Station::Impl::Stop(bool all_met, const std::string& why, int64_t line,
                         std::vector<StationEvent>* events) {
  done = true;
  targets_met = all_met;
  stop_reason = why;
  StationEvent e = Event(StationEventKind::kStopped, line);
  e.pose = static_cast<int>(accepted.size());
  e.reason = why;
  e.u = u;
  e.targets_met = all_met;
  events->push_back(e);
}

std::vector<Session> Station::Impl::Sessions() const {
  std::vector<Session> out;
  const char* names[kAxes] = {"ax_lsb", "ay_lsb", "az_lsb", "gx_lsb", "gy_lsb", "gz_lsb"};
  for (size_t r = 0; r < records.size(); ++r) {
    const bool used = std::any_of(accepted.begin(), accepted.end(), [&](const AcceptedPose& p) {
      return p.record == static_cast<int>(r);
    });
    if (!used) continue;
    const Record& rec = records[r];
    Session s;
    s.path = records.size() > 1 ? fmt::format("{}#record{}", source, r + 1) : source;
    s.format = SessionFormat::kRaw;
    s.rows = static_cast<int64_t>(rec.t_s.size());
    s.columns = {"t_s"};
    Tag tag;
    tag.sensor = o.sensor;
    tag.source_name = s.path;
    tag.t_s = rec.t_s;
    tag.line = rec.line;
    for (int a = 0; a < kAxes; ++a) {
      Quantity q;
      q.name = names[a];
      q.unit = "LSB";
      q.values.reserve(rec.counts.size());
      for (const auto& c : rec.counts) q.values.push_back(c[a]);
      tag.quantities.push_back(std::move(q));
      s.columns.push_back(names[a]);
    }
    s.tags.push_back(std::move(tag));
    out.push_back(std::move(s));
  }
  return out;
}

std::vector<AnnotatedSegment> Station::Impl::Segments() const {
  std::map<int, int> input;  // record -> index among the records with poses
  for (const AcceptedPose& p : accepted) input.emplace(p.record, 0);
  int next = 0;
  for (auto& [record, index] : input) index = next++;
  std::vector<AnnotatedSegment> out;
  for (size_t i = 0; i < accepted.size(); ++i) {
    const AcceptedPose& p = accepted[i];
    const Record& rec = records[static_cast<size_t>(p.record)];
    AnnotatedSegment a;
    a.kind = SegmentKind::kStatic;
    a.input = input[p.record];
    a.start_s = rec.t_s[p.begin];
    a.end_s = rec.t_s[p.end];
    a.line = static_cast<int>(i) + 1;
    out.push_back(a);
  }
  return out;
}

CalibrationOptions Station::Impl::FitOptions() const {
  CalibrationOptions c = o.calibration;
  c.sensor = o.sensor;
  c.accel_fs_g = o.accel_fs_g;
  c.gyro_fs_dps = o.gyro_fs_dps;
  c.annotated_segments = Segments();
  c.segments_path = source + " (the station's accepted poses)";
  c.compare_models = true;
  return c;
}

// ---- public --------------------------------------------------------------------------------

Station::Station(StationOptions options, std::string source)
    : impl_(std::make_unique<Impl>(std::move(options), std::move(source))) {
  std::string why;
  METRO_CHECK(impl_->o.IsValid(&why));
}

Station::~Station() = default;

std::vector<StationEvent> Station::Feed(const RawSample& sample, int64_t line) {
  std::vector<StationEvent> events;
  if (impl_->done) return events;
  if (impl_->AppendSample(sample, line, &events)) impl_->UpdateStillness(&events, line);
  return events;
}

std::vector<StationEvent> Station::Gap(const std::string& why) {
  std::vector<StationEvent> events;
  if (impl_->done) return events;
  StationEvent e = impl_->Event(StationEventKind::kGap, 0);
  e.reason = why + ": a new record starts when samples come again; poses taken are kept";
  if (impl_->mode == Mode::kHolding) e.reason += "; the hold in progress is dropped";
  events.push_back(e);
  impl_->StartRecord();
  return events;
}

std::vector<StationEvent> Station::Finish(const std::string& why) {
  std::vector<StationEvent> events;
  if (impl_->done) return events;
  // A hold that reached its dwell before the stream ended is a pose (its last window trimmed).
  if (impl_->mode == Mode::kHolding && impl_->hold_complete) {
    const size_t k = impl_->records.back().t_s.size() - 1;
    impl_->EndHold(k - impl_->width, 0, &events);
    if (impl_->done) return events;
  }
  const bool met = !impl_->u.empty() && std::all_of(impl_->u.begin(), impl_->u.end(),
                                                    [](const ConstantU& c) { return c.met; });
  std::string reason = why + fmt::format(" after {} poses; ", impl_->accepted.size());
  reason += met                ? "every target met"
            : impl_->u.empty() ? "the calibration is " + impl_->u_status
                               : "targets not met";
  impl_->Stop(met, reason, 0, &events);
  return events;
}

bool Station::Done() const { return impl_->done; }
bool Station::TargetsMet() const { return impl_->targets_met; }
int Station::AcceptedPoses() const { return static_cast<int>(impl_->accepted.size()); }
std::vector<Session> Station::Sessions() const { return impl_->Sessions(); }
std::vector<AnnotatedSegment> Station::Segments() const { return impl_->Segments(); }
CalibrationOptions Station::FitOptions() const { return impl_->FitOptions(); }

Result<Calibration> Station::FitCalibration() const {
  const std::vector<Session> sessions = Sessions();
  if (sessions.empty()) return MakeError("the station took no pose: nothing to fit");
  std::vector<const Session*> ptrs;
  for (const Session& s : sessions) ptrs.push_back(&s);
  return CalibrateSessions(ptrs, FitOptions());
}

StationView Station::View() const {
  const Impl& m = *impl_;
  StationView v;
  // While a complete hold waits for the operator to move, the next pose is the one after it.
  std::vector<Eigen::Vector3d> taken = m.TakenUps();
  if (m.mode == Mode::kHolding && m.hold_complete) taken.push_back(m.hold_up);
  const int next = ChooseNextPose(m.o.protocol, m.poses, taken, m.o.min_separation_deg);
  if (next >= 0 && !m.done) {
    v.next_pose = m.poses[static_cast<size_t>(next)].name;
    v.next_up = m.poses[static_cast<size_t>(next)].up_body;
    v.turn = TurnInstruction(m.current_up, v.next_up);
  }
  v.stillness = m.stillness;
  v.holding = m.mode == Mode::kHolding;
  v.too_close = m.mode == Mode::kTooClose;
  if (v.holding) {
    const size_t k = m.records.back().t_s.size() - 1;
    const size_t usable = k >= m.hold_begin + m.width ? k - m.width - m.hold_begin + 1 : 0;
    v.held_s = static_cast<double>(usable) / m.o.rate_hz;
    v.dwell_s = static_cast<double>(m.dwell_needed) / m.o.rate_hz;
  }
  v.taken = m.TakenUps();
  v.poses = m.poses;
  for (const ProtocolPose& p : m.poses) {
    v.covered.push_back(NearestWithin(v.taken, p.up_body, m.o.min_separation_deg) >= 0);
  }
  v.u = m.u;
  v.u_status = m.u_status;
  v.done = m.done;
  v.stop_reason = m.stop_reason;
  v.records = static_cast<int>(m.records.size());
  v.samples = m.samples;
  return v;
}

}  // namespace metro::station
