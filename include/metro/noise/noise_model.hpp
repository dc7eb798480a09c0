// IEEE Std 952-1997 Annex C noise model of a rate quantity [q] (gyro deg/s, accel g, ...).
//
//   AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2
//
//   Q  quantization noise   [q]*s        (white angle/phase noise of variance Q^2)
//   N  random walk (ARW/VRW) [q]*sqrt(s) (two-sided rate PSD N^2; one-sided density sqrt2 N)
//   B  bias instability     [q]          (two-sided rate PSD B^2 / (2 pi f))
//   K  rate random walk     [q]/sqrt(s)  (two-sided rate PSD K^2 / (2 pi f)^2)
//   R  rate ramp            [q]/s        (deterministic drift of the rate)
//
// Zero for every coefficient means a noiseless rate. The model is linear in the squared
// coefficients c = [Q^2, N^2, B^2, K^2, R^2]; NoiseBasis() gives the factor multiplying each.
//
// The Hadamard variance (overlapping or not) has the same white term and different factors
// for the others (derived from its transfer function (8/3) sin^6(pi f tau) / (pi f tau)^2):
//   HVAR(tau) = (10/3) Q^2 / tau^2 + N^2 / tau + ((4 ln2 - 1.5 ln3) / pi) B^2 + K^2 tau / 6
// and is blind to a rate ramp. The modified Allan variance has no tau-independent white-PM
// factor, so the model is not defined for it (NoiseBasis returns false).
#pragma once

#include <array>
#include <string>

#include "metro/noise/allan.hpp"

namespace metro {

enum class NoiseTerm {
  kQuantization = 0,
  kRandomWalk = 1,
  kBiasInstability = 2,
  kRateRandomWalk = 3,
  kRateRamp = 4,
};
inline constexpr int kNoiseTermCount = 5;
inline constexpr std::array<NoiseTerm, kNoiseTermCount> kAllNoiseTerms = {
    NoiseTerm::kQuantization, NoiseTerm::kRandomWalk, NoiseTerm::kBiasInstability,
    NoiseTerm::kRateRandomWalk, NoiseTerm::kRateRamp};

// JSON key of a term: "quantization", "random_walk", "bias_instability",
// "rate_random_walk", "rate_ramp".
std::string NoiseTermKey(NoiseTerm term);

// Log-log slope of the deviation where the term dominates: -1, -1/2, 0, +1/2, +1.
double NoiseTermSlope(NoiseTerm term);

// Power-law exponent alpha of the rate PSD (S_y ~ f^alpha) that the term represents, as
// used by the EDF: Q -> 2 (white PM), N -> 0, B -> -1, K -> -2; a ramp is not noise and is
// mapped to -2 (the most pessimistic EDF).
int NoiseTermAlpha(NoiseTerm term);

// Factor f_term(tau) such that variance(tau) = sum_term f_term(tau) * coefficient_term^2 for the
// given estimator family. Returns false (and leaves *factor untouched) when the model is not
// defined for the estimator (mdev, or a rate ramp under a Hadamard variance).
bool NoiseBasis(AllanEstimator estimator, NoiseTerm term, double tau_s, double* factor);

}  // namespace metro
