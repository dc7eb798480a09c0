// Independent rate-noise generators for the noise-fit coverage tests (issue #36 part 8): the
// discretizations a real sensor or another project's simulator may use, written apart from
// tests/noise/noise_simulation.hpp (whose generators are those the IEEE 952 model describes
// exactly). Tests only.
//
// Point-sampled Kasdin flicker (Kasdin, Proc. IEEE 83 (1995) 802; Kasdin & Walter 1992): the
// fractional integration y = (1 - z^-1)^(-1/2) w of white w of standard deviation B, by the
// filter h_0 = 1, h_k = h_(k-1) (k - 1/2) / k applied as a linear convolution through FFTW.
// Two-sided PSD B^2 / (2 sin(pi nu)) per cycle-per-sample, i.e. B^2 / (2 pi f) at low
// frequency: its Allan variance tends to (2 ln2 / pi) B^2 and at m = 1 is exactly
// B^2 * 2 / pi (1/ln2 = 1.443 times the IEEE 952 factor).
//
// Integrating sampler: every process is generated on a grid `oversample` times finer and each
// rate sample is the mean of its `oversample` fine samples (white of density N, Kasdin flicker
// of level B, random walk K on the fine grid). The flicker's point-sampling excess moves to
// m_fine = oversample (1.5 % at 8, 0.5 % at 16 in variance); the random walk's to
// K^2 tau0^2 / (6 oversample^2 tau).
//
// Kalibr discrete model (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model), as the simulator of
// allan_variance_ros writes it: per sample of period dt,
//   y_k = b_k + sigma_w / sqrt(dt) n_k,   b_(k+1) = b_k + sigma_b sqrt(dt) n'_k
// with sigma_w the noise density (IEEE 952 N = sigma_w) and sigma_b the bias random walk
// (K = sigma_b; the point-sampled walk adds K^2 dt^2 / (6 tau) to the Allan variance).
#pragma once

#include <fftw3.h>

#include <cmath>
#include <cstdint>
#include <mutex>
#include <random>
#include <vector>

namespace metro::testing {

// Kasdin flicker of level b (innovations of standard deviation b), n point samples.
inline std::vector<double> KasdinFlickerPointSampled(size_t n, double b, uint64_t seed) {
  std::vector<double> out(n, 0.0);
  if (n == 0 || !(b > 0.0)) return out;
  size_t size = 1;
  while (size < 2 * n) size *= 2;  // linear convolution of two length-n sequences
  const size_t bins = size / 2 + 1;
  double* h = fftw_alloc_real(size);
  double* w = fftw_alloc_real(size);
  fftw_complex* hf = fftw_alloc_complex(bins);
  fftw_complex* wf = fftw_alloc_complex(bins);
  fftw_plan ph, pw, back;
  {
    static std::mutex mutex;  // FFTW planning is not thread-safe
    std::lock_guard<std::mutex> lock(mutex);
    ph = fftw_plan_dft_r2c_1d(static_cast<int>(size), h, hf, FFTW_ESTIMATE);
    pw = fftw_plan_dft_r2c_1d(static_cast<int>(size), w, wf, FFTW_ESTIMATE);
    back = fftw_plan_dft_c2r_1d(static_cast<int>(size), wf, w, FFTW_ESTIMATE);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, b);
  for (size_t k = 0; k < size; ++k) {
    h[k] = 0.0;
    w[k] = 0.0;
  }
  h[0] = 1.0;
  for (size_t k = 1; k < n; ++k) {
    h[k] = h[k - 1] * (static_cast<double>(k) - 0.5) / static_cast<double>(k);
  }
  for (size_t k = 0; k < n; ++k) w[k] = normal(rng);
  fftw_execute(ph);
  fftw_execute(pw);
  for (size_t j = 0; j < bins; ++j) {
    const double re = hf[j][0] * wf[j][0] - hf[j][1] * wf[j][1];
    const double im = hf[j][0] * wf[j][1] + hf[j][1] * wf[j][0];
    wf[j][0] = re;
    wf[j][1] = im;
  }
  fftw_execute(back);
  for (size_t k = 0; k < n; ++k) out[k] = w[k] / static_cast<double>(size);
  {
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    fftw_destroy_plan(ph);
    fftw_destroy_plan(pw);
    fftw_destroy_plan(back);
  }
  fftw_free(h);
  fftw_free(w);
  fftw_free(hf);
  fftw_free(wf);
  return out;
}

// Kalibr's discrete white noise and bias random walk (see the file comment), n samples of
// period dt_s: sigma_w [q*sqrt(s)] (noise density), sigma_b [q/sqrt(s)] (bias random walk).
inline std::vector<double> KalibrImuRate(size_t n, double dt_s, double sigma_w, double sigma_b,
                                         uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> y(n);
  double bias = 0.0;
  for (size_t k = 0; k < n; ++k) {
    y[k] = bias + sigma_w / std::sqrt(dt_s) * normal(rng);
    bias += sigma_b * std::sqrt(dt_s) * normal(rng);
  }
  return y;
}

// White (N) + flicker (B) + random walk (K) rate, IEEE 952 coefficients in base units.
// Point-sampled: white of standard deviation N / sqrt(tau0), Kasdin flicker, a walk with steps
// K sqrt(tau0).
inline std::vector<double> PointSampledNbk(size_t n, double tau0_s, double n_coef, double b_coef,
                                           double k_coef, uint64_t seed) {
  std::vector<double> y = KalibrImuRate(n, tau0_s, n_coef, k_coef, seed * 5 + 1);
  const std::vector<double> f = KasdinFlickerPointSampled(n, b_coef, seed * 5 + 2);
  for (size_t k = 0; k < n; ++k) y[k] += f[k];
  return y;
}

// The same three terms through an integrating sampler: generated on a grid `oversample` times
// finer (tau0 / oversample) and averaged over each sample interval.
inline std::vector<double> IntegratingNbk(size_t n, double tau0_s, double n_coef, double b_coef,
                                          double k_coef, uint64_t seed, size_t oversample = 16) {
  const size_t fine_n = n * oversample;
  const double fine_dt = tau0_s / static_cast<double>(oversample);
  const std::vector<double> fine = PointSampledNbk(fine_n, fine_dt, n_coef, b_coef, k_coef, seed);
  std::vector<double> y(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    double sum = 0.0;
    for (size_t j = 0; j < oversample; ++j) sum += fine[k * oversample + j];
    y[k] = sum / static_cast<double>(oversample);
  }
  return y;
}

// Kalibr's model (white and bias random walk as allan_variance_ros simulates them) with a
// point-sampled Kasdin flicker added for the bias instability B.
inline std::vector<double> KalibrNbk(size_t n, double tau0_s, double n_coef, double b_coef,
                                     double k_coef, uint64_t seed) {
  std::vector<double> y = KalibrImuRate(n, tau0_s, n_coef, k_coef, seed * 11 + 7);
  const std::vector<double> f = KasdinFlickerPointSampled(n, b_coef, seed * 11 + 8);
  for (size_t k = 0; k < n; ++k) y[k] += f[k];
  return y;
}

}  // namespace metro::testing
