// Power-law noise identification by the lag-1 autocorrelation (W. J. Riley and
// C. A. Greenhall, "Power law noise identification using the lag 1 autocorrelation",
// Proc. 18th EFTF (2004), as used by Stable32 and NIST SP 1065).
//
// At averaging factor m the phase x is decimated, z_k = x_{k m} (equivalently the rate is
// averaged over m samples). The series is differenced until it looks stationary:
//   r1 = sum (z_k - zbar)(z_{k+1} - zbar) / sum (z_k - zbar)^2,   delta = r1 / (1 + r1)
// stopping at the first d_diff with delta < 0.25 or d_diff = d_max (2 for Allan, 3 for
// Hadamard variances). Then p = -2 (delta + d_diff) estimates the phase PSD exponent and
// alpha = round(p) + 2 is the rate (frequency) exponent S_y ~ f^alpha, clamped to
// [2 - 2 d_max, 2] so that the EDF exists: 2 white PM (quantization), 1 flicker PM,
// 0 white rate (angle random walk), -1 flicker rate (bias instability), -2 random-walk rate.
#pragma once

#include <cstdint>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

struct NoiseIdentification {
  int alpha = 0;          // Rounded and clamped rate exponent.
  double p = 0.0;         // Unrounded phase exponent estimate.
  double lag1_acf = 0.0;  // r1 of the last series examined.
  int differences = 0;    // d_diff.
  int64_t n_points = 0;   // Decimated points used.
};

// d_max: 2 for Allan variances, 3 for Hadamard. At most `max_points` decimated points are used
// (the first ones): r1 then has a sampling standard deviation near 1/sqrt(max_points) = 0.001,
// far below the 0.25 decision steps, and the cost per tau stays bounded for long records.
// (ComputeAllan passes AllanOptions::max_points_noise_id, 2^16 unless set: r1 scatter ~0.004.)
// Errors: m < 1, d_max not 2 or 3, fewer than `min_points` decimated points (min_points >= 8),
// or a constant series.
Result<NoiseIdentification> IdentifyNoiseLag1(const std::vector<double>& phase, int64_t m,
                                              int d_max, int64_t min_points = 30,
                                              int64_t max_points = int64_t{1} << 20);

// The same on the n_phase phase points at phase (not null when n_phase > 0).
Result<NoiseIdentification> IdentifyNoiseLag1(const double* phase, int64_t n_phase, int64_t m,
                                              int d_max, int64_t min_points = 30,
                                              int64_t max_points = int64_t{1} << 20);

}  // namespace metro
