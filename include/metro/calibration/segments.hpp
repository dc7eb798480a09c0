// Segmentation of a calibration record into static poses, rotation-table runs and the hand
// rotations between static poses.
//
// Static detector: for every sample k, v(k) = sum over the three axes of the variance of the
// samples in the window centred on k (window_s wide), computed separately for the
// accelerometer and the gyroscope. Each sensor's noise floor f is the 5th percentile of its
// v(k) (a calibration record is far more than 5 % static). A sample is static when
// v_accel(k) < c * f_accel and v_gyro(k) < c * f_gyro (the gyro test is skipped when there is no
// gyroscope), it is not saturated and the table is not turning. Runs of static samples at least
// min_static_s long are static intervals; neighbouring intervals whose accelerometer means
// differ by less than 3 sqrt(f_accel) are one pose and are merged.
//
// The threshold factor c is chosen automatically: every c of `threshold_factors` is tried and
// the one that yields the most static intervals wins (imu_tk instead keeps the threshold with the
// smallest accelerometer residual, which favours fewer intervals). When several factors reach
// the maximum, the median of them is taken, away from both the threshold that just admits the
// poses and the one that starts to merge them. Because the window is centred, each interval
// ends about half a window before the motion starts.
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

enum class SegmentKind { kStatic, kTable, kRotation };
const char* SegmentKindName(SegmentKind kind);  // "static", "table", "rotation"

struct Segment {
  SegmentKind kind = SegmentKind::kStatic;
  int piece = 0;              // Index of the input file (session) the segment is in.
  size_t begin = 0;           // First sample index.
  size_t end = 0;             // One past the last sample index.
  double start_s = 0;         // t_s of the first sample.
  double end_s = 0;           // t_s of the last sample.
  double table_rate_dps = 0;  // kTable only.
  bool used = true;           // False when the fit could not use it (see note).
  std::string note;           // Why it was not used, or what is special about it.
};

struct SegmentationOptions {
  double window_s = 1.0;      // Width of the centred variance window.
  double min_static_s = 1.0;  // Shortest static interval kept.
  std::vector<double> threshold_factors = {1.5, 2, 3, 4, 6, 8, 12, 16, 24, 32};
  double table_settle_s = 0.5;  // Trimmed from both ends of each table run.
  double min_table_s = 1.0;     // Shortest table run kept (after trimming).
  double max_gap_factor = 5.0;  // A time step above this times the median step is a gap.

  bool IsValid(std::string* why) const;
};

// Input of the detector: one record of one tag. Vectors are per sample; gyro, temp and
// table_rate_dps may be empty. `saturated[k]` excludes sample k from static intervals.
struct SegmentationInput {
  const std::vector<double>* t_s = nullptr;
  const std::vector<Eigen::Vector3d>* accel = nullptr;
  const std::vector<Eigen::Vector3d>* gyro = nullptr;
  const std::vector<double>* table_rate_dps = nullptr;
  const std::vector<unsigned char>* saturated = nullptr;
  int piece = 0;
};

struct SegmentationSummary {
  std::vector<Segment> segments;  // Ordered by begin; tables may lie inside rotations.
  double threshold_factor = 0;    // The chosen c.
  double accel_floor = 0;         // f_accel [input unit^2].
  double gyro_floor = 0;          // f_gyro [input unit^2] (0 without a gyroscope).
  int static_count = 0;
  int table_count = 0;
  int rotation_count = 0;
};

// Segments one record. Preconditions: t_s and accel non-empty and of equal size, t_s
// increasing, options valid (checked with METRO_CHECK).
SegmentationSummary DetectSegments(const SegmentationInput& input,
                                   const SegmentationOptions& options);

}  // namespace metro
