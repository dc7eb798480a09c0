// The resolution of quantized data: the step of the lattice its values sit on (a receiver's
// 0.01 deg, raw LSB counts), for displays that must not bin finer than the data can say
// (JCGM 100 F.2.2.1: the resolution of an indication).
#pragma once

#include <cstddef>
#include <vector>

namespace metro {

// The smallest difference q between the distinct finite values of `x` (values closer than
// 1e-9 of the data's scale count as one) when at least 95 % of the gaps between consecutive
// distinct values are whole multiples of q (within 1e-3 q) and there are at least 5 distinct
// values; 0 otherwise (continuous data, too few values).
// Quantized values are ordered by lattice bucket, not sorted, when they sit on the lattice a
// strided sample suggests (the same gaps as sorting, bit for bit); otherwise they are sorted.
double QuantizationStep(const std::vector<double>& x);
double QuantizationStep(const double* x, size_t n);

}  // namespace metro
