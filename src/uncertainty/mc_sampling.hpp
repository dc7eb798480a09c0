// Random-variate generation for the Monte Carlo method (JCGM 101:2008 6.4, Annex C), by
// blocks of trials so that the arithmetic runs as vector code.
//
// WordSource: the random 64-bit words of one chunk of trials. Four pcg64 engines (pcg-cpp,
// PCG XSL RR 128/64) advance in lockstep and their outputs are interleaved in a buffer:
// one pcg64 step is a chain of dependent 128-bit multiplies, four independent chains keep
// the multiplier busy (~1.4 ns instead of ~2-3 ns per word on the project's machine).
// Engine j (0..3) of chunk c starts at state splitmix64(splitmix64(seed) + 4c + j) on
// stream 4c + j, so the words depend on (seed, c) only.
//
// Uniforms:
//   U52(w) = the double with exponent 0 and mantissa w >> 12, minus 1
//                                                    in [0, 1), 52 random bits; bit operations
//                                                    only, so blocks of them are vector code
//   S32(h) = (h + 1/2) 2^-31, h a 32-bit half of w taken as a signed integer,
//                                                    in (-1, 1), symmetric, never 0
// Two S32 values come from one word: they feed the polar methods below, whose
// acceptance test and result need no more resolution (the lattice of 2^-31 moves any
// probability by less than 1e-9, far below the Monte Carlo noise of 1e7 trials, 3e-4).
//
// Student t (Bailey's polar method, exact; R. W. Bailey, Math. Comp. 62 (1994) 779-781):
//   (u, v) uniform in the unit disc (S32 pairs, rejected while w = u^2 + v^2 >= 1),
//   t = u sqrt(nu (w^(-2/nu) - 1) / w)  ~  t_nu
// w^(-2/nu) - 1 = expm1(e), e = -2 ln(w) / nu >= 0, computed as exp(e) - 1 for e >= 1e-3
// (relative error < 3e-13) and by its Taylor series to e^5/120 below (relative error
// < 2e-15), so very large nu keeps full accuracy. log, exp, sqrt and the division run as
// Eigen array expressions (vectorised), from a second build for AVX2 + FMA when the CPU has
// both (mc_sampling_avx2.cpp; ~2.5x faster than SSE2). The two builds round differently in
// the last bits, so samples are reproducible for a seed on one machine class, not bitwise
// across machines with and without AVX2.
//
// Arcsine on [-1, 1] (6.4.6): for (s, t) uniform in the unit disc, with w = s^2 + t^2,
// (s^2 - t^2) / w = cos(2 phi) with phi uniform: the law of sin(2 pi r) of 6.4.6.4.
//
// The accept/reject loops are branch-free: every candidate is written, the write index
// advances only when it is accepted.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <pcg_random.hpp>

namespace metro {
namespace internal {

uint64_t SplitMix64(uint64_t x);

class WordSource {
 public:
  using result_type = uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return ~result_type{0}; }

  WordSource(uint64_t seed, uint64_t chunk);

  result_type operator()() {
    if (next_ == kWords) Refill();
    return words_[next_++];
  }

  // Up to `count` next words in one piece: *words points at them, the return value says
  // how many (at least 1; fewer than `count` only at the end of the buffer).
  static constexpr size_t kWords = 256;
  size_t Take(size_t count, const uint64_t** words) {
    if (next_ == kWords) Refill();
    const size_t got = std::min(count, kWords - next_);
    *words = words_ + next_;
    next_ += got;
    return got;
  }

 private:
  void Refill();

  pcg64 engines_[4];
  alignas(64) uint64_t words_[kWords];
  size_t next_ = kWords;
};

inline double S32(uint32_t h) {
  return (static_cast<double>(static_cast<int32_t>(h)) + 0.5) * 0x1.0p-31;
}

// Scratch arrays for the block samplers, n values each.
struct SamplerScratch {
  explicit SamplerScratch(size_t n);
  double* a() { return a_.get(); }
  double* b() { return b_.get(); }
  double* c() { return c_.get(); }

 private:
  std::unique_ptr<double[]> a_;
  std::unique_ptr<double[]> b_;
  std::unique_ptr<double[]> c_;
};

// out[k] = location + scale t_k, k < n, t_k ~ t_nu (Bailey). Precondition: nu > 0, scratch
// holds n values.
void StudentTBlock(WordSource& words, double nu, double location, double scale, size_t n,
                   SamplerScratch* scratch, double* out);

// The arithmetic of StudentTBlock for accepted disc points u[k], w[k] (e: scratch). There
// is one build per instruction set: BaileyKernel(true) is the AVX2 + FMA build when the CPU
// runs it (the one StudentTBlock uses), else the baseline build; BaileyKernel(false) is
// always the baseline build.
using BaileyFn = void (*)(const double* u, const double* w, size_t n, double nu, double location,
                          double scale, double* e_scratch, double* out);
BaileyFn BaileyKernel(bool allow_avx2);

// out[k] = U52 of the next n words (rectangular, triangular, trapezoidal and curvilinear
// trapezoid inputs are affine in these, JCGM 101 6.4.2-6.4.5).
void UniformBlock(WordSource& words, size_t n, double* out);

// out[k] = centre + half_width c_k, c_k ~ arcsine on [-1, 1].
void ArcsineBlock(WordSource& words, double centre, double half_width, size_t n,
                  SamplerScratch* scratch, double* out);

}  // namespace internal
}  // namespace metro
