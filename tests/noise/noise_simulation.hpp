// Power-law rate noise with known IEEE 952 coefficients (tests only).
//
// White rate:    y_k = (N / sqrt(tau0)) w_k                 AVAR = N^2 / tau (exact)
// Flicker rate:  Kasdin & Walter (1992) fractional integration of order 1/2 of white noise
//                of standard deviation B: h_0 = 1, h_k = h_{k-1} (k - 1/2) / k. Its two-sided
//                PSD is B^2 tau0 / (2 sin(pi f tau0)) ~ B^2 / (2 pi f), the IEEE 952 bias-
//                instability spectrum with coefficient B, so AVAR -> (2 ln2 / pi) B^2.
// Rate RW:       b_{k+1} = b_k + K sqrt(tau0) w_k            AVAR ~ K^2 tau / 3
// White / flicker phase (alpha = 2, 1): first differences of a white / Kasdin phase series.
#pragma once

#include <complex>
#include <cstdint>
#include <random>
#include <unsupported/Eigen/FFT>
#include <vector>

namespace metro::testing {

inline std::vector<double> WhiteNoise(size_t n, double sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma);
  std::vector<double> w(n);
  for (double& v : w) v = normal(rng);
  return w;
}

// Kasdin-Walter flicker (1/f) noise from white innovations of standard deviation sigma.
inline std::vector<double> FlickerNoise(size_t n, double sigma, uint64_t seed) {
  const std::vector<double> w = WhiteNoise(n, sigma, seed);
  size_t size = 1;
  while (size < 2 * n) size *= 2;
  std::vector<double> h(size, 0.0), wp(size, 0.0);
  h[0] = 1.0;
  for (size_t k = 1; k < n; ++k) h[k] = h[k - 1] * (static_cast<double>(k) - 0.5) / k;
  for (size_t k = 0; k < n; ++k) wp[k] = w[k];
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> hf, wf;
  fft.fwd(hf, h);
  fft.fwd(wf, wp);
  for (size_t k = 0; k < hf.size(); ++k) hf[k] *= wf[k];
  std::vector<double> out;
  fft.inv(out, hf);
  out.resize(n);
  return out;
}

inline std::vector<double> RandomWalk(size_t n, double step_sigma, uint64_t seed) {
  std::vector<double> w = WhiteNoise(n, step_sigma, seed);
  double b = 0.0;
  for (double& v : w) {
    b += v;
    v = b;
  }
  return w;
}

// Rate series with S_y ~ f^alpha, alpha in {2, 1, 0, -1, -2}.
inline std::vector<double> PowerLawRate(int alpha, size_t n, uint64_t seed) {
  switch (alpha) {
    case 2:
    case 1: {
      const std::vector<double> x =
          alpha == 2 ? WhiteNoise(n + 1, 1.0, seed) : FlickerNoise(n + 1, 1.0, seed);
      std::vector<double> y(n);
      for (size_t k = 0; k < n; ++k) y[k] = x[k + 1] - x[k];
      return y;
    }
    case 0:
      return WhiteNoise(n, 1.0, seed);
    case -1:
      return FlickerNoise(n, 1.0, seed);
    default:
      return RandomWalk(n, 1.0, seed);
  }
}

// White + flicker + random-walk rate with IEEE 952 coefficients N [q*sqrt(s)], B [q],
// K [q/sqrt(s)] at sample period tau0.
inline std::vector<double> ImuRate(size_t n, double tau0_s, double n_coef, double b_coef,
                                   double k_coef, uint64_t seed) {
  std::vector<double> y = WhiteNoise(n, n_coef / std::sqrt(tau0_s), seed);
  const std::vector<double> f = FlickerNoise(n, b_coef, seed + 1);
  const std::vector<double> r = RandomWalk(n, k_coef * std::sqrt(tau0_s), seed + 2);
  for (size_t k = 0; k < n; ++k) y[k] += f[k] + r[k];
  return y;
}

}  // namespace metro::testing
