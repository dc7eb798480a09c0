// Segmentation of a calibration record into static poses, rotation-table runs, steady
// rotations and the hand rotations between static poses.
//
// Static detector: for every sample k, v(k) = sum over the three axes of the variance of the
// samples in the window centred on k (window_s wide), computed separately for the
// accelerometer and the gyroscope. Each sensor's noise floor f is the 5th percentile of its
// v(k) (a calibration record is far more than 5 % static). A sample is still when
// v_accel(k) < c * f_accel and v_gyro(k) < c * f_gyro (the gyro test is skipped when there is no
// gyroscope), it is not saturated and the table is not turning. Runs of still samples at least
// min_static_s long are still periods.
//
// One pose, several still periods: neighbouring still periods whose accelerometer means differ
// by less than 3 sqrt(f_accel) and whose gyroscope means differ by less than 3 sqrt(f_gyro),
// with nothing turning between them, belong to one pose (Segment::pose). They stay separate
// static segments: the samples between them (a knock, a saturated burst, a shift of the hand)
// are never averaged into the pose; they form a rotation segment whose note names the
// disturbance.
//
// Steady rotations are not static: a still period whose mean gyroscope rate differs from the
// gyroscope bias by more than a limit is a turn at constant rate (a turntable whose rate the
// record does not give, or gives as 0). Its accelerometer is as quiet as a pose's when the
// axis is vertical, but its gyroscope mean is not a bias. It becomes a kSteady segment,
// excluded with a note giving its rate. The limit is max_static_rate_dps when
// gyro_units_per_dps is known; else (unit-free) 10 times the median deviation of the still
// periods and at least 30 per-sample noise standard deviations.
//
// The gyroscope bias follows the temperature (MPU6050: tens of mdeg/s per degC, the
// simulator draws up to 0.16 deg/s/degC): over a 15 -> 45 degC ramp it moves by several deg/s,
// as much as a slow turn. So, with a temperature column, the bias is a line in temperature,
//
//   bias(T) = b0 + b1 (T - T_ref),   per axis, T_ref the median of the still periods' T,
//
// fitted to the still periods' mean rates and mean temperatures by Siegel's repeated median
// (Biometrika 69 (1982) 242: b1 = med_i med_j (m_j - m_i) / (T_j - T_i), b0 = med_i (m_i -
// b1 (T_i - T_ref)); it stands up to almost half the periods being turns), and each still
// period is compared with the bias at its own temperature. Without temperatures (or all at one
// temperature) b1 = 0 and b0 is the per-axis median, as before. The comparison allows for the
// fit's own uncertainty: a still period is a steady rotation when
//   |m - bias(T)| > limit + 3 u(bias(T)),
// u per axis = 1.2533 s sqrt(1/P + (T - mean T)^2 / sum (T_i - mean T)^2) (the least-squares
// form with the median's efficiency factor sqrt(pi/2)), s = 1.4826 median |residual| over the
// P still periods. A rotation about the vertical is the only turn that keeps the accelerometer
// still, and its rate stands out of the line as a whole; a bias that follows the temperature
// lies on it.
//
// The threshold factor c is chosen automatically: every c of `threshold_factors` is tried and
// the one that yields the most poses wins (imu_tk instead keeps the threshold with the
// smallest accelerometer residual, which favours fewer intervals). When several factors reach
// the maximum, the median of them is taken, away from both the threshold that just admits the
// poses and the one that starts to merge them. Because the window is centred, each interval
// ends about half a window before the motion starts.
//
// Short poses: still periods too short for min_static_s are looked for again with a short
// window (a quarter of window_s, at most 0.25 s) and counted with their durations, so that a
// refusal for too few poses can say how many shorter ones were recorded and which
// min_static_s would accept them.
//
// Table runs: maximal runs of equal, non-zero table_rate_dps (NaN = unknown), less
// table_settle_s at both ends, at least min_table_s long. Rotations: the samples between two
// consecutive static intervals (hand rotations, possibly with table runs inside).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace metro {

enum class SegmentKind { kStatic, kTable, kRotation, kSteady };
// "static", "table", "rotation", "steady_rotation"
const char* SegmentKindName(SegmentKind kind);

struct Segment {
  SegmentKind kind = SegmentKind::kStatic;
  int piece = 0;              // Index of the input file (session) the segment is in.
  size_t begin = 0;           // First sample index.
  size_t end = 0;             // One past the last sample index.
  double start_s = 0;         // t_s of the first sample.
  double end_s = 0;           // t_s of the last sample.
  double table_rate_dps = 0;  // kTable only.
  int pose = -1;              // kStatic: still periods of one pose share this index.
  // kSteady: the mean gyroscope rate less the bias, in input units (norm) and in deg/s when
  // the units are known (else NaN).
  double steady_rate = 0;
  double steady_rate_dps = 0;
  bool used = true;  // False when the fit could not use it (see note).
  std::string note;  // Why it was not used, or what is special about it.
};

struct SegmentationOptions {
  double window_s = 1.0;      // Width of the centred variance window.
  double min_static_s = 1.0;  // Shortest still period kept; below window_s it is also the window.
  std::vector<double> threshold_factors = {1.5, 2, 3, 4, 6, 8, 12, 16, 24, 32};
  double table_settle_s = 0.5;  // Trimmed from both ends of each table run.
  double min_table_s = 1.0;     // Shortest table run kept (after trimming).
  double max_gap_factor = 5.0;  // A time step above this times the median step is a gap.
  // Input gyroscope units per deg/s (e.g. 131 for raw counts at +-250 deg/s; 1 for deg/s);
  // 0 = unknown, the unit-free steady-rotation limit is used.
  double gyro_units_per_dps = 0;
  double max_static_rate_dps = 2.0;  // Steady-rotation limit (see above).

  bool IsValid(std::string* why) const;
};

// Input of the detector: one record of one tag. Vectors are per sample; gyro, temp_c and
// table_rate_dps may be empty. `saturated[k]` excludes sample k from static intervals.
// temp_c (degC, NaN = no reading) lets the steady-rotation test follow the bias in temperature.
struct SegmentationInput {
  const std::vector<double>* t_s = nullptr;
  const std::vector<Eigen::Vector3d>* accel = nullptr;
  const std::vector<Eigen::Vector3d>* gyro = nullptr;
  const std::vector<double>* temp_c = nullptr;
  const std::vector<double>* table_rate_dps = nullptr;
  const std::vector<unsigned char>* saturated = nullptr;
  int piece = 0;
};

struct SegmentationSummary {
  std::vector<Segment> segments;  // Ordered by begin; tables may lie inside rotations.
  double threshold_factor = 0;    // The chosen c.
  double accel_floor = 0;         // f_accel [input unit^2].
  double gyro_floor = 0;          // f_gyro [input unit^2] (0 without a gyroscope).
  int static_count = 0;           // Static segments (still periods).
  int pose_count = 0;             // Distinct poses among them (Segment::pose).
  int table_count = 0;
  int rotation_count = 0;
  int steady_count = 0;  // Steady rotations excluded.
  // The gyroscope bias the steady-rotation test used (input units; zero without a gyroscope or
  // with fewer than 2 poses): bias(T) = gyro_bias + gyro_bias_per_c (T - gyro_bias_t_ref_c).
  // gyro_bias_temperature is false when no temperature was used (gyro_bias_per_c = 0).
  bool gyro_bias_temperature = false;
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias_per_c = Eigen::Vector3d::Zero();  // [input unit / degC]
  double gyro_bias_t_ref_c = 0;
  int disturbed_poses = 0;  // Poses whose still periods a disturbance separates.
  // Still periods too short for min_static_s (found with the short window): how many, their
  // durations, and the min_static_s (with window_s no longer) that would accept them all.
  int short_static_count = 0;
  double short_static_min_s = 0;
  double short_static_max_s = 0;
  double suggested_min_static_s = 0;
};

// Segments one record. Preconditions: t_s and accel non-empty and of equal size, t_s
// increasing, options valid (checked with METRO_CHECK).
SegmentationSummary DetectSegments(const SegmentationInput& input,
                                   const SegmentationOptions& options);

}  // namespace metro
