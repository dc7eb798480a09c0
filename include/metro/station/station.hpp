// The calibration station's live guide (issue #44, docs/station.md): raw counts in, one sample
// at a time; events out (a pose accepted or rejected and why, the live u of every constant, the
// stop), and a view of its state for the terminal. The fit, its u and the final calibration are
// the calibration module's own (CalibrateTag, CalibrateSessions): the guide has no fitter.
//
// The guide runs these stages on every sample, in this order:
//
//   record      AppendSample          the sample joins the current record (a gap in the tag's
//                                     clock or a lost port starts a new one: the gyroscope
//                                     cannot be integrated across it)
//   stillness   StillnessDetector     trailing window variance of each sensor against its noise
//                                     floor (the 20th percentile of the record's windows)
//   hold        StartHold, EndHold    a still period is a hold; one too close to an accepted pose
//                                     is said and not used; a saturated sample makes it unusable
//   dwell       DwellNeeded           how long this hold must last: the noise of its mean (AR(1)
//                                     effective n, JCGM 100:2008 4.2.3, 4.2.7) below
//                                     dwell_fraction x the target, and at least min_dwell_s
//   acceptance  EndHold               a hold that ends (motion) after its dwell is a pose; one
//                                     disturbed before (a knock, moved too early) is rejected
//                                     and repeated, never averaged in
//   live u      LiveUncertainty       CalibrateTag on the records so far with the accepted poses
//                                     as annotated static segments: the u of every constant,
//                                     expressed against its target (ConstantU)
//   next pose   ChooseNextPose        protocol.hpp
//   stop        DecideStop            every target met; or the protocol complete and a target
//                                     not met: which constant, its u and why
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "metro/calibration/calibrate.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/station/protocol.hpp"
#include "metro/station/raw_line.hpp"

namespace metro::station {

struct StationOptions {
  int sensor = 1;  // The tag's number in calibration.json and the tags file.
  Protocol protocol = Protocol::kSixFace;
  double rate_hz = 0;  // The stream's sample rate [Hz] (required; times are index / rate_hz).
  double accel_fs_g = 2.0;
  double gyro_fs_dps = 250.0;
  // Targets (k = 1) of every constant, expressed as the error it makes (ConstantU): the
  // accelerometer's at 1 g [mg], the gyroscope's bias [deg/s] and its scale and cross-axis
  // terms at gyro_reference_dps [deg/s].
  double target_u_accel_mg = 0.5;
  double target_u_gyro_dps = 0.05;
  double gyro_reference_dps = 100.0;
  double window_s = 0.25;       // Stillness window.
  double still_factor = 6.0;    // Still when the window variance < still_factor x floor.
  double min_dwell_s = 1.5;     // Shortest hold accepted.
  double max_dwell_s = 30.0;    // Longest dwell asked for (a noisier tag is asked for more poses).
  double dwell_fraction = 0.5;  // A pose mean's noise below this fraction of the target.
  double min_separation_deg = 20.0;  // Closer to an accepted pose: "too close".
  double same_pose_deg = 5.0;        // A rejected hold repeated within this is "the same pose".
  double gap_factor = 5.0;           // t_ms step > gap_factor / rate_hz: a new record.
  // The fit's options (models, gravity, loss); sensor, full scales and segments are set by
  // the station. Defaults: the full models, as `calibrate fit`.
  CalibrationOptions calibration;

  bool IsValid(std::string* why) const;
};

// One constant's u against its target. The accelerometer's constants as the error they make at
// 1 g [mg]: b: u(b) k; k: u(k) / k x 1 g; cross-axis terms: u [rad] x 1 g. The gyroscope's
// [deg/s]: b: u(b) k; k: u(k) / k x gyro_reference_dps; terms: u [rad] x gyro_reference_dps.
struct ConstantU {
  std::string name;  // NamedConstants' name, e.g. "accel.k_x".
  double u = 0;      // In `unit`.
  double target = 0;
  std::string unit;  // "mg" or "deg/s".
  bool met = false;  // u <= target.
};

enum class StationEventKind {
  kHoldStarted,   // A still period began (pose named, with its nearest protocol pose).
  kHoldComplete,  // Its dwell is reached: move on.
  kPoseAccepted,
  kPoseRejected,  // reason: disturbed before its dwell, saturated, the stream stopped.
  kTooClose,      // A still period within min_separation_deg of an accepted pose.
  kUncertainty,   // The live u after an accepted pose (or why there is none yet).
  kTargetMet,     // A constant's u reached its target (once per constant).
  kGap,           // The stream stopped (lost port, a jump in the tag's clock): a new record.
  kStopped,       // The guide's stop: reason, and the u of every constant.
};
const char* StationEventKindName(StationEventKind kind);  // "pose_accepted", ...

struct StationEvent {
  StationEventKind kind = StationEventKind::kHoldStarted;
  double t_s = 0;            // Of the stream (the record's time).
  int64_t line = 0;          // Source line of the sample that made the event.
  int pose = 0;              // Accepted pose number (1-based), 0 when none.
  std::string pose_name;     // The protocol pose nearest to the hold (or the one asked for).
  std::string reason;        // Why (rejections, too close, the stop), or what to do next.
  std::vector<ConstantU> u;  // kUncertainty, kTargetMet (that constant), kStopped.
  bool targets_met = false;  // kStopped: every target met.
};

// "pose_accepted t_s=12.40 pose=3 name="X up" ..." : one plain line per event (no newline).
std::string EventText(const StationEvent& event);
// The same as one JSON object (no newline): {"event":"pose_accepted","t_s":12.4,...}.
std::string EventJson(const StationEvent& event);

// What the terminal view shows (StationView is a snapshot; Station::View()).
struct StationView {
  std::string next_pose;  // Name of the pose to take next ("" when done).
  Eigen::Vector3d next_up = Eigen::Vector3d::UnitZ();
  std::string turn;                    // From the current orientation to the next pose.
  double stillness = 0;                // Window variance / still threshold (< 1: still).
  bool holding = false;                // In a usable hold.
  bool too_close = false;              // In a still period too close to an accepted pose.
  double held_s = 0;                   // Usable time of the current hold.
  double dwell_s = 0;                  // Dwell the current hold needs.
  std::vector<Eigen::Vector3d> taken;  // Accepted poses' up directions.
  std::vector<ProtocolPose> poses;     // The protocol's.
  std::vector<bool> covered;           // Per protocol pose: an accepted pose within separation.
  std::vector<ConstantU> u;            // Latest live u (empty before the first fit).
  std::string u_status;  // Why there is no u yet ("needs 4 more distinct orientations ...").
  bool done = false;
  std::string stop_reason;
  int records = 1;
  int64_t samples = 0;
};

class Station {
 public:
  // Precondition: options.IsValid().
  Station(StationOptions options, std::string source);
  ~Station();
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  // One sample (line: its source line, for events). Returns the events it caused.
  std::vector<StationEvent> Feed(const RawSample& sample, int64_t line);
  // The stream stopped (a port that disappeared; EOF of a followed file that was truncated):
  // the hold in progress is dropped, the next sample starts a new record. Poses taken stay.
  std::vector<StationEvent> Gap(const std::string& why);
  // The stream ended before the stop rule: stop now (reason given), with what was taken.
  std::vector<StationEvent> Finish(const std::string& why);

  bool Done() const;
  bool TargetsMet() const;
  StationView View() const;
  int AcceptedPoses() const;

  // The records as sessions (one per record, columns t_s ax_lsb .. gz_lsb, path
  // "<source>#<record>") and the accepted poses as annotated static segments into them.
  std::vector<Session> Sessions() const;
  std::vector<AnnotatedSegment> Segments() const;
  // The fit options the guide uses (models from options.calibration; full scales, sensor and
  // segments from the station); compare_models as `calibrate fit`.
  CalibrationOptions FitOptions() const;
  // The final fit: CalibrateSessions over Sessions() with FitOptions(), as `calibrate fit
  // SESSION... --segments` makes it.
  Result<Calibration> FitCalibration() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The terminal view (docs/station.md "The view"): the pose to take and the turn to it, the
// stillness meter, the hold's time left, the coverage map, the u of every constant against its
// target (green when met, with ANSI colours when `color`). Lines end in "\n"; no cursor moves.
std::string RenderStationView(const StationView& view, const std::string& title, bool color);
// The coverage map: `rows` elevations (+90 .. -90 deg) by `cols` azimuths (-180 .. 180 deg) of
// the body's up direction; '#' taken, '@' the next pose, '.' a protocol pose, ' ' none.
std::vector<std::string> CoverageMap(const StationView& view, int rows, int cols);

// The accepted poses as `calibrate fit --segments FILE` reads them (segment_file.hpp):
// "kind,start_s,end_s,input", times as the session CSV writes them (shortest round trip), input
// 1-based.
std::string SegmentsCsvText(const std::vector<AnnotatedSegment>& segments);

// The u of every constant of a tag's calibration against the station's targets (ConstantU).
std::vector<ConstantU> ConstantUncertainties(const TagCalibration& tag,
                                             const StationOptions& options);

// Distinct orientations the accelerometer model needs: its free parameters + 1
// (docs/calibration-model.md "Uncertainty": fewer is refused).
int MinOrientations(ModelKind accel_model);

// The samples a hold must last for its mean's noise to fall to dwell_fraction x target
// (JCGM 100:2008 4.2.3 with the AR(1) effective number of observations, 4.2.7): per axis
// n = s^2 (1 + rho) / (1 - rho) / (fraction x target)^2, s and rho the hold's samples' standard
// deviation and lag-1 autocorrelation (clamped to 0 .. 0.9), in the target's unit at the nominal
// sensitivity; the largest over both sensors' axes, at least min_dwell_s x rate_hz and at
// most max_dwell_s x rate_hz. `accel`, `gyro`: the hold's counts [LSB].
int64_t DwellNeeded(const std::vector<Eigen::Vector3d>& accel,
                    const std::vector<Eigen::Vector3d>& gyro, const StationOptions& options);

}  // namespace metro::station
