#include "uncertainty/mc_sampling.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cstring>

#define METRO_MC_KERNEL_NAMESPACE baseline
#include "uncertainty/mc_bailey_kernel.hpp"

namespace metro {
namespace internal {

uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

WordSource::WordSource(uint64_t seed, uint64_t chunk) {
  const uint64_t base = SplitMix64(seed);
  for (uint64_t j = 0; j < 4; ++j) {
    const uint64_t id = 4 * chunk + j;
    engines_[j] = pcg64(SplitMix64(base + id), id);
  }
}

void WordSource::Refill() {
  pcg64& e0 = engines_[0];
  pcg64& e1 = engines_[1];
  pcg64& e2 = engines_[2];
  pcg64& e3 = engines_[3];
  for (size_t k = 0; k < kWords; k += 4) {
    words_[k] = e0();
    words_[k + 1] = e1();
    words_[k + 2] = e2();
    words_[k + 3] = e3();
  }
  next_ = 0;
}

SamplerScratch::SamplerScratch(size_t n)
    : a_(new double[n]), b_(new double[n]), c_(new double[n]) {}

#if METRO_MC_AVX2
// mc_sampling_avx2.cpp
void BaileyTransformAvx2(const double* u, const double* w, size_t n, double nu, double location,
                         double scale, double* e_scratch, double* out);
#endif

BaileyFn BaileyKernel(bool allow_avx2) {
#if METRO_MC_AVX2
  if (allow_avx2 && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    return &BaileyTransformAvx2;
  }
#else
  (void)allow_avx2;
#endif
  return &baseline::BaileyTransform;
}

namespace {

using Array = Eigen::Map<Eigen::ArrayXd>;

// Fills first[k] = s or s^2 - t^2 (per kDifference) and w[k] = s^2 + t^2 for n points
// uniform in the open unit disc (without the centre, which S32 never gives). Candidates are
// made by batches of words (vector code), then the accepted ones are packed.
template <bool kDifference>
void DiscPoints(WordSource& words, size_t n, double* first, double* w) {
  constexpr size_t kBatch = 64;
  double cand_first[kBatch];
  double cand_w[kBatch];
  size_t k = 0;
  while (k < n) {
    // Acceptance is pi/4: ask for a little more than the expected need.
    const uint64_t* r = nullptr;
    const size_t got = words.Take(std::min(kBatch, (n - k) * 4 / 3 + 4), &r);
    for (size_t j = 0; j < got; ++j) {
      const double s = S32(static_cast<uint32_t>(r[j] >> 32));
      const double t = S32(static_cast<uint32_t>(r[j]));
      cand_first[j] = kDifference ? s * s - t * t : s;
      cand_w[j] = s * s + t * t;
    }
    for (size_t j = 0; j < got && k < n; ++j) {
      first[k] = cand_first[j];
      w[k] = cand_w[j];
      k += cand_w[j] < 1.0 ? 1 : 0;
    }
  }
}

}  // namespace

void StudentTBlock(WordSource& words, double nu, double location, double scale, size_t n,
                   SamplerScratch* scratch, double* out) {
  DiscPoints<false>(words, n, scratch->a(), scratch->b());
  // Bailey (1994): t = u sqrt(nu (w^(-2/nu) - 1) / w).
  static const BaileyFn kernel = BaileyKernel(true);
  kernel(scratch->a(), scratch->b(), n, nu, location, scale, scratch->c(), out);
}

void UniformBlock(WordSource& words, size_t n, double* out) {
  static_assert(sizeof(double) == sizeof(uint64_t), "IEEE 754 binary64 expected");
  size_t k = 0;
  while (k < n) {
    const uint64_t* r = nullptr;
    const size_t got = words.Take(n - k, &r);
    // 1 + U52 as bits (exponent of 1.0, random mantissa), copied into the doubles.
    uint64_t bits[WordSource::kWords];
    for (size_t j = 0; j < got; ++j) bits[j] = (r[j] >> 12) | 0x3FF0000000000000ULL;
    std::memcpy(out + k, bits, got * sizeof(uint64_t));
    for (size_t j = 0; j < got; ++j) out[k + j] -= 1.0;
    k += got;
  }
}

void ArcsineBlock(WordSource& words, double centre, double half_width, size_t n,
                  SamplerScratch* scratch, double* out) {
  DiscPoints<true>(words, n, scratch->a(), scratch->b());
  const Eigen::Index size = static_cast<Eigen::Index>(n);
  Array d(scratch->a(), size);
  Array w(scratch->b(), size);
  Array x(out, size);
  x = centre + half_width * d / w;  // JCGM 101 6.4.6.4 (same law, see the header)
}

}  // namespace internal
}  // namespace metro
