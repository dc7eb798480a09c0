// The tag's error curve over the table's range, by weighted least squares
// (docs/accuracy.md, "Error model").
//
//   e(theta) = c0 + s theta + a1 cos(theta) + b1 sin(theta) + a2 cos(2 theta) + b2 sin(2 theta)
//
// theta [deg] is the reference angle as the table reports it; c0, a1, b1, a2, b2 [deg];
// s [deg/deg] (the scale error). A model is a subset of these terms; all zero is a perfect
// tag. Harmonics are a mounting misalignment of the tag on the table (a tilted axis makes the
// error vary once per turn; an eccentric or elliptic one twice).
//
// Weighted least squares (JCGM 100:2008 H.3 for the calibration-curve framework): with the
// design matrix J (m x p), weights W = diag(1/u_i^2) and the plateau errors e_i,
//   beta = (J^T W J)^-1 J^T W e,  chi2 = sum (e_i - J_i beta)^2 / u_i^2,  nu = m - p
//   C = (J^T W J)^-1, multiplied by chi2/nu when chi2/nu > 1 (scatter beyond the stated u_i,
//   e.g. hysteresis and repeatability: the covariance is then that of a fit whose weights
//   are only relative; `covariance_scaled` says so)
//   u_fit(theta) = sqrt(g^T C g),  g = dE/dbeta at theta          (JCGM 100 5.2.2 with the
//   covariances of the fitted parameters, as H.3.4 does for b(t))
//
// Order rule (stated in every report): a model with p parameters needs at least p + 2
// distinct reference angles; the first harmonic also needs an angular span >= 180 deg and
// the second >= 270 deg. kAuto takes the largest model the data support.
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// kHysteresis: h d / 2 with d = +1 on a plateau reached turning up, -1 turning down, 0 for the
// first (direction unknown); h = up minus down. With it the curve's other parameters are
// those of the mean of the up and down curves (unbiased when the turning points are visited
// in one direction only), and Predict(theta) (d = 0) is that mean curve.
enum class ErrorTerm { kOffset, kScale, kCos1, kSin1, kCos2, kSin2, kHysteresis };

// Parameter names "c0_deg", "scale", "a1_deg", "b1_deg", "a2_deg", "b2_deg", "h_deg".
const char* ErrorTermName(ErrorTerm term);
// Basis function of a term at theta_deg (1, theta_deg, cos theta, ..., d / 2).
double ErrorTermBasis(ErrorTerm term, double theta_deg, int direction = 0);

enum class ErrorModel {
  kAuto,
  kLinear,     // c0 + s theta
  kHarmonic1,  // + a1 cos + b1 sin
  kHarmonic2,  // + a2 cos 2 + b2 sin 2
};
const char* ErrorModelName(ErrorModel model);  // "auto", "linear", "harmonic1", "harmonic2"
Result<ErrorModel> ParseErrorModel(const std::string& name);
std::vector<ErrorTerm> ErrorModelTerms(ErrorModel model);

// The rule above, in words, for reports.
extern const char* const kErrorModelOrderRule;

struct FitPoint {
  double theta_deg = 0.0;
  double value_deg = 0.0;
  double u_deg = 0.0;  // > 0
  int direction = 0;   // For kHysteresis: +1 reached turning up, -1 down, 0 unknown.
};

// Distinct reference angles (closer than match_deg count as one) and the angular span.
struct AngleCoverage {
  size_t distinct = 0;
  double span_deg = 0.0;
};
AngleCoverage CoverageOf(const std::vector<FitPoint>& points, double match_deg);

// Picks the model for `requested` under the order rule. Errors name what to collect, e.g.
// "the harmonic1 error model has 4 parameters and needs plateaus at >= 6 distinct
// reference angles spanning >= 180 deg; found 4 angles spanning 90 deg: collect ...".
Result<ErrorModel> ChooseErrorModel(const std::vector<FitPoint>& points, ErrorModel requested,
                                    double match_deg);

struct HarmonicFit {
  std::vector<ErrorTerm> terms;
  std::vector<double> params;                   // beta, in the terms' order.
  std::vector<double> u;                        // sqrt(diag C).
  std::vector<std::vector<double>> covariance;  // C (p x p), scaled if covariance_scaled.
  double chi2 = 0.0;
  int dof = 0;  // m - p
  double reduced_chi2 = 0.0;
  bool covariance_scaled = false;
  std::vector<double> residuals_deg;  // e_i - fit, per point.
  double residual_rms_deg = 0.0;      // sqrt(sum r_i^2 / (m - p)), unweighted; 0 when m = p.

  double Predict(double theta_deg, int direction = 0) const;
  double PredictionU(double theta_deg, int direction = 0) const;  // u_fit(theta)
};

// Fits `terms` to the points. Errors: fewer points than parameters, a non-positive u, a
// singular design (angles that cannot separate the terms).
Result<HarmonicFit> FitHarmonicModel(const std::vector<FitPoint>& points,
                                     const std::vector<ErrorTerm>& terms);

}  // namespace metro
