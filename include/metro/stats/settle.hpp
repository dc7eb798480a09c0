// Start-up transient detection (`--settle auto`).
//
// MSER-5, the Marginal Standard Error Rule on batch means of 5 (White, Simulation 69
// (1997) 323; Franklin & White, WSC 2008). The series is cut into m batches of 5 and
// their means b_j. For each candidate truncation d (batches), over the first half of
// the series,
//   MSER(d) = 1/(m - d)^2 * sum_{j > d} (b_j - mean_{j > d} b)^2
// is the squared standard error of the mean of what remains; the truncation is the d that
// minimises it. A transient raises the spread of the early batches more than dropping
// them costs in sample size, so the minimum falls where the transient has decayed into
// the noise. The result is in samples (5 d).
#pragma once

#include <cstddef>

namespace metro {

struct SettleResult {
  size_t samples = 0;     // Observations to drop from the start.
  double mser = 0.0;      // MSER at the chosen truncation.
  bool at_limit = false;  // The minimum was at the half-series limit: the series may
                          // not have settled (or drifts); inspect it.
};

// Requires n >= 10 (two batches); with fewer, returns 0 samples.
SettleResult DetectSettleMser5(const double* values, size_t n);

}  // namespace metro
