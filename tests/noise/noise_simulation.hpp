// Power-law rate noise with known IEEE 952 coefficients (tests only).
//
// White rate:    y_k = (N / sqrt(tau0)) w_k                 AVAR = N^2 / tau (exact)
// Flicker rate:  Kasdin & Walter (1992) fractional integration of order 1/2 of white noise
//                of standard deviation B: h_0 = 1, h_k = h_{k-1} (k - 1/2) / k. Its two-sided
//                PSD is B^2 tau0 / (2 sin(pi f tau0)) ~ B^2 / (2 pi f), the IEEE 952 bias-
//                instability spectrum with coefficient B, so AVAR -> (2 ln2 / pi) B^2.
// Rate RW:       b_{k+1} = b_k + K sqrt(tau0) w_k            AVAR ~ K^2 tau / 3
// White / flicker phase (alpha = 2, 1): first differences of a white / Kasdin phase series.
//
// Ieee952Rate() sums all five IEEE Std 952-1997 Annex C terms with known coefficients, the
// truth of the noise-fit coverage tests (noise_fit_coverage_test.cpp):
//   Q  white phase x_k of std Q, y_k = (x_{k+1} - x_k) / tau0      AVAR = 3 Q^2 / tau^2 (exact)
//   N  white rate of std N / sqrt(tau0)                            AVAR = N^2 / tau (exact)
//   B  flicker rate whose samples are the averages over tau0 of a continuous process of
//      two-sided PSD B^2 / (2 pi f) (an integrating sampler), so AVAR = (2 ln2 / pi) B^2 at
//      every tau = m tau0, m >= 1. Spectral synthesis (FlickerAveragedFftw): the aliased,
//      sinc^2-weighted PSD S(f) = B^2 tau0 sin^2(pi f tau0) / (2 pi^3) sum_k |f tau0 + k|^-3
//      on the bins of a periodic series 16 times the record (at least 4 times beyond 2^23
//      points), of which the first n samples are kept; frequencies below 1 / (16 T) are
//      missing. With only 5.8 times (1 h) the long-tau correlations of a B-alone record were
//      off enough for the 95 % coverage of B to fall to 80 %; 16 times restores 98 %. (Sampled
//      Kasdin flicker, FlickerNoise(), reads 44 % above the formula at tau = tau0 and 5 % at 4 tau0
//      (its PSD is not aliased): the fit rightly sees a white-phase excess there.)
//   K  averages over tau0 of a Brownian rate of diffusion K^2      AVAR = K^2 tau / 3 (exact; the
//      plain sampled random walk RandomWalk() adds K^2 tau0^2 / (6 tau), a white-rate term)
//   R  deterministic ramp R k tau0                                 AVAR = R^2 tau^2 / 2 (exact)
#pragma once

#include <fftw3.h>

#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
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

// sum_{k >= 0} (a + k)^-3, the Hurwitz zeta(3, a), for a >= 8 by Euler-Maclaurin:
// 1/(2a^2) + 1/(2a^3) + 1/(4a^4) - 1/(12a^6) + 1/(12a^8), next term -0.15 a^-10 (< 2e-10 here).
inline double HurwitzZeta3Tail(double a) {
  const double r = 1.0 / a, r2 = r * r;
  return r2 * (0.5 + r * (0.5 + r * (0.25 + r2 * (-1.0 / 12.0 + r2 / 12.0))));
}

// The aliasing sum sum_k |u + k|^-3 over all integers k, 0 < u < 1: the 17 nearest terms
// exactly, the tails by HurwitzZeta3Tail. Within 6e-12 of -(psi''(u) + psi''(1 - u)) / 2
// (Boost polygamma) at 1 h bins; the former 401-term sum of std::pow took about 30 s of CPU per
// test process for the 2^22 bins of a 1 h record, this one 0.3 s.
inline double AliasedCubeSum(double u) {
  double s = 0.0;
  for (int k = -8; k <= 8; ++k) {
    const double a = std::fabs(u + k);
    s += 1.0 / (a * a * a);
  }
  return s + HurwitzZeta3Tail(9.0 + u) + HurwitzZeta3Tail(9.0 - u);
}

// Flicker rate averaged over each sample interval (see the file comment), B in [q].
inline std::vector<double> FlickerAveragedFftw(size_t n, double tau0_s, double b_coef,
                                               uint64_t seed) {
  size_t size = 1;
  // At least 16 times the record up to 2^23 points, at least 4 times beyond (1 h at 100 Hz:
  // 23 times, 6 h: 7.8 times).
  while (size < 4 * n || (size < 16 * n && size < (size_t{1} << 23))) size *= 2;
  const size_t bins = size / 2 + 1;
  static std::mutex mutex;
  // Never destroyed (as src/stats/type_a.cpp's plans): the plans stay reachable until the
  // process ends, so the leak checker does not report FFTW's allocations behind them.
  static auto* plans =
      new std::map<size_t, std::pair<fftw_plan, std::shared_ptr<std::vector<double>>>>();
  fftw_complex* spec = fftw_alloc_complex(bins);
  double* real = reinterpret_cast<double*>(spec);  // in place: 2 * bins doubles
  fftw_plan plan = nullptr;
  std::shared_ptr<std::vector<double>> amp;
  {
    std::lock_guard<std::mutex> lock(mutex);  // FFTW planning is not thread-safe
    auto it = plans->find(size);
    if (it == plans->end()) {
      const fftw_plan p = fftw_plan_dft_c2r_1d(static_cast<int>(size), spec, real,
                                               FFTW_ESTIMATE | FFTW_DESTROY_INPUT);
      // a_j = sqrt(2 S(f_j) df) per unit B, f_j = j / (size tau0), as a fraction of 1 / tau0.
      auto a = std::make_shared<std::vector<double>>(bins, 0.0);
      for (size_t j = 1; j < bins; ++j) {
        const double u = static_cast<double>(j) / static_cast<double>(size);
        const double zeta = AliasedCubeSum(u);
        const double sin_u = std::sin(M_PI * u);
        const double psd = sin_u * sin_u / (2.0 * M_PI * M_PI * M_PI) * zeta;  // S / (B^2 tau0)
        (*a)[j] = std::sqrt(2.0 * psd / static_cast<double>(size));  // df = 1 / (size tau0)
      }
      it = plans->emplace(size, std::make_pair(p, a)).first;
    }
    plan = it->second.first;
    amp = it->second.second;
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  spec[0][0] = spec[0][1] = 0.0;
  for (size_t j = 1; j < bins; ++j) {
    const double a = (*amp)[j] * b_coef;
    spec[j][0] = 0.5 * a * normal(rng);
    spec[j][1] = j + 1 == bins ? 0.0 : 0.5 * a * normal(rng);
  }
  if (bins > 1) spec[bins - 1][0] *= 2.0 / std::sqrt(2.0);  // Nyquist bin: real, full weight
  fftw_execute_dft_c2r(plan, spec, real);
  std::vector<double> out(real, real + n);
  fftw_free(spec);
  (void)tau0_s;  // the PSD scales with tau0, the rate samples do not
  return out;
}

// Rate with the IEEE 952 coefficients coef = [Q, N, B, K, R] (base units; 0 leaves a term out)
// at sample period tau0_s; see the file comment.
inline std::vector<double> Ieee952Rate(size_t n, double tau0_s, const std::array<double, 5>& coef,
                                       uint64_t seed) {
  std::vector<double> y(n, 0.0);
  if (coef[0] > 0.0) {
    const std::vector<double> x = WhiteNoise(n + 1, coef[0], seed * 7 + 1);
    for (size_t k = 0; k < n; ++k) y[k] += (x[k + 1] - x[k]) / tau0_s;
  }
  if (coef[1] > 0.0) {
    const std::vector<double> w = WhiteNoise(n, coef[1] / std::sqrt(tau0_s), seed * 7 + 2);
    for (size_t k = 0; k < n; ++k) y[k] += w[k];
  }
  if (coef[2] > 0.0) {
    const std::vector<double> f = FlickerAveragedFftw(n, tau0_s, coef[2], seed * 7 + 3);
    for (size_t k = 0; k < n; ++k) y[k] += f[k];
  }
  if (coef[3] > 0.0) {
    // Averages over each interval of a Brownian rate W: W_k + dW_k / 2 + eta_k, with
    // var(dW_k) = K^2 tau0 and eta_k independent of variance K^2 tau0 / 12.
    std::mt19937_64 rng(seed * 7 + 4);
    std::normal_distribution<double> normal(0.0, 1.0);
    const double step = coef[3] * std::sqrt(tau0_s);
    double w = 0.0;
    for (size_t k = 0; k < n; ++k) {
      const double dw = step * normal(rng);
      y[k] += w + 0.5 * dw + step / std::sqrt(12.0) * normal(rng);
      w += dw;
    }
  }
  if (coef[4] > 0.0) {
    for (size_t k = 0; k < n; ++k) y[k] += coef[4] * tau0_s * static_cast<double>(k);
  }
  return y;
}

}  // namespace metro::testing
