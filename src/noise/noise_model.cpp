#include "metro/noise/noise_model.hpp"

#include <cmath>

namespace metro {

std::string NoiseTermKey(NoiseTerm term) {
  switch (term) {
    case NoiseTerm::kQuantization:
      return "quantization";
    case NoiseTerm::kRandomWalk:
      return "random_walk";
    case NoiseTerm::kBiasInstability:
      return "bias_instability";
    case NoiseTerm::kRateRandomWalk:
      return "rate_random_walk";
    case NoiseTerm::kRateRamp:
      return "rate_ramp";
  }
  return "?";
}

double NoiseTermSlope(NoiseTerm term) {
  switch (term) {
    case NoiseTerm::kQuantization:
      return -1.0;
    case NoiseTerm::kRandomWalk:
      return -0.5;
    case NoiseTerm::kBiasInstability:
      return 0.0;
    case NoiseTerm::kRateRandomWalk:
      return 0.5;
    case NoiseTerm::kRateRamp:
      return 1.0;
  }
  return 0.0;
}

int NoiseTermAlpha(NoiseTerm term) {
  switch (term) {
    case NoiseTerm::kQuantization:
      return 2;
    case NoiseTerm::kRandomWalk:
      return 0;
    case NoiseTerm::kBiasInstability:
      return -1;
    case NoiseTerm::kRateRandomWalk:
    case NoiseTerm::kRateRamp:
      return -2;
  }
  return 0;
}

bool NoiseBasis(AllanEstimator estimator, NoiseTerm term, double tau_s, double* factor) {
  const double kPi = 3.14159265358979323846;
  const bool allan = estimator == AllanEstimator::kOadev || estimator == AllanEstimator::kAdev;
  const bool hadamard = estimator == AllanEstimator::kOhdev || estimator == AllanEstimator::kHdev;
  if (!allan && !hadamard) return false;
  double f = 0.0;
  switch (term) {
    case NoiseTerm::kQuantization:  // IEEE Std 952-1997 Annex C: 3 Q^2 / tau^2
      f = (allan ? 3.0 : 10.0 / 3.0) / (tau_s * tau_s);
      break;
    case NoiseTerm::kRandomWalk:  // N^2 / tau
      f = 1.0 / tau_s;
      break;
    case NoiseTerm::kBiasInstability:  // (2 ln2 / pi) B^2
      f = allan ? 2.0 * std::log(2.0) / kPi : (4.0 * std::log(2.0) - 1.5 * std::log(3.0)) / kPi;
      break;
    case NoiseTerm::kRateRandomWalk:  // K^2 tau / 3 (Allan), K^2 tau / 6 (Hadamard)
      f = allan ? tau_s / 3.0 : tau_s / 6.0;
      break;
    case NoiseTerm::kRateRamp:  // R^2 tau^2 / 2; the Hadamard variance cancels a ramp.
      if (!allan) return false;
      f = tau_s * tau_s / 2.0;
      break;
  }
  *factor = f;
  return true;
}

}  // namespace metro
