#include "metro/accuracy/error_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace metro {
namespace {

constexpr double kRadPerDeg = M_PI / 180.0;

size_t HarmonicOrder(const std::vector<ErrorTerm>& terms) {
  size_t order = 0;
  for (ErrorTerm t : terms) {
    if (t == ErrorTerm::kCos1 || t == ErrorTerm::kSin1) order = std::max<size_t>(order, 1);
    if (t == ErrorTerm::kCos2 || t == ErrorTerm::kSin2) order = 2;
  }
  return order;
}

// Span the rule asks for, per harmonic order.
double RequiredSpanDeg(size_t order) { return order == 0 ? 0.0 : order == 1 ? 180.0 : 270.0; }

}  // namespace

const char* const kErrorModelOrderRule =
    "a model with p parameters needs plateaus at >= p + 2 distinct reference angles; the first "
    "harmonic also needs an angular span >= 180 deg, the second >= 270 deg; auto takes the "
    "largest model the data support";

const char* ErrorTermName(ErrorTerm term) {
  switch (term) {
    case ErrorTerm::kOffset:
      return "c0_deg";
    case ErrorTerm::kScale:
      return "scale";
    case ErrorTerm::kCos1:
      return "a1_deg";
    case ErrorTerm::kSin1:
      return "b1_deg";
    case ErrorTerm::kCos2:
      return "a2_deg";
    case ErrorTerm::kSin2:
      return "b2_deg";
    case ErrorTerm::kHysteresis:
      return "h_deg";
  }
  return "?";
}

double ErrorTermBasis(ErrorTerm term, double theta_deg, int direction) {
  const double th = theta_deg * kRadPerDeg;
  switch (term) {
    case ErrorTerm::kOffset:
      return 1.0;
    case ErrorTerm::kScale:
      return theta_deg;
    case ErrorTerm::kCos1:
      return std::cos(th);
    case ErrorTerm::kSin1:
      return std::sin(th);
    case ErrorTerm::kCos2:
      return std::cos(2.0 * th);
    case ErrorTerm::kSin2:
      return std::sin(2.0 * th);
    case ErrorTerm::kHysteresis:
      return 0.5 * direction;
  }
  return 0.0;
}

const char* ErrorModelName(ErrorModel model) {
  switch (model) {
    case ErrorModel::kAuto:
      return "auto";
    case ErrorModel::kLinear:
      return "linear";
    case ErrorModel::kHarmonic1:
      return "harmonic1";
    case ErrorModel::kHarmonic2:
      return "harmonic2";
  }
  return "?";
}

Result<ErrorModel> ParseErrorModel(const std::string& name) {
  for (ErrorModel m :
       {ErrorModel::kAuto, ErrorModel::kLinear, ErrorModel::kHarmonic1, ErrorModel::kHarmonic2}) {
    if (name == ErrorModelName(m)) return m;
  }
  return MakeError("unknown error model '" + name +
                   "' (expected auto, linear, harmonic1 or harmonic2)");
}

std::vector<ErrorTerm> ErrorModelTerms(ErrorModel model) {
  std::vector<ErrorTerm> terms = {ErrorTerm::kOffset, ErrorTerm::kScale};
  if (model == ErrorModel::kHarmonic1 || model == ErrorModel::kHarmonic2) {
    terms.push_back(ErrorTerm::kCos1);
    terms.push_back(ErrorTerm::kSin1);
  }
  if (model == ErrorModel::kHarmonic2) {
    terms.push_back(ErrorTerm::kCos2);
    terms.push_back(ErrorTerm::kSin2);
  }
  return terms;
}

AngleCoverage CoverageOf(const std::vector<FitPoint>& points, double match_deg) {
  AngleCoverage c;
  if (points.empty()) return c;
  std::vector<double> theta;
  for (const FitPoint& p : points) theta.push_back(p.theta_deg);
  std::sort(theta.begin(), theta.end());
  c.distinct = 1;
  for (size_t i = 1; i < theta.size(); ++i) {
    if (theta[i] - theta[i - 1] > match_deg) ++c.distinct;
  }
  c.span_deg = theta.back() - theta.front();
  return c;
}

Result<ErrorModel> ChooseErrorModel(const std::vector<FitPoint>& points, ErrorModel requested,
                                    double match_deg) {
  const AngleCoverage c = CoverageOf(points, match_deg);
  auto supported = [&](ErrorModel m) {
    const std::vector<ErrorTerm> terms = ErrorModelTerms(m);
    return c.distinct >= terms.size() + 2 && c.span_deg >= RequiredSpanDeg(HarmonicOrder(terms));
  };
  auto need = [&](ErrorModel m) {
    const std::vector<ErrorTerm> terms = ErrorModelTerms(m);
    const size_t order = HarmonicOrder(terms);
    return MakeError(fmt::format(
        "fewer points than the {} error model needs: it has {} parameters and needs plateaus at "
        ">= {} distinct reference angles{}; found {} angle(s) spanning {:.6g} deg. Collect "
        "dwell plateaus at more table angles{}",
        ErrorModelName(m), terms.size(), terms.size() + 2,
        order > 0 ? fmt::format(" spanning >= {:.0f} deg", RequiredSpanDeg(order)) : "", c.distinct,
        c.span_deg,
        order > 0 ? fmt::format(" over at least {:.0f} deg", RequiredSpanDeg(order)) : ""));
  };
  if (requested != ErrorModel::kAuto) {
    if (!supported(requested)) return need(requested);
    return requested;
  }
  for (ErrorModel m : {ErrorModel::kHarmonic2, ErrorModel::kHarmonic1, ErrorModel::kLinear}) {
    if (supported(m)) return m;
  }
  return need(ErrorModel::kLinear);
}

double HarmonicFit::Predict(double theta_deg, int direction) const {
  double y = 0.0;
  for (size_t j = 0; j < terms.size(); ++j) {
    y += params[j] * ErrorTermBasis(terms[j], theta_deg, direction);
  }
  return y;
}

double HarmonicFit::PredictionU(double theta_deg, int direction) const {
  // JCGM 100 5.2.2 with the fitted parameters' covariance: u^2 = g^T C g.
  double v = 0.0;
  for (size_t i = 0; i < terms.size(); ++i) {
    for (size_t j = 0; j < terms.size(); ++j) {
      v += ErrorTermBasis(terms[i], theta_deg, direction) * covariance[i][j] *
           ErrorTermBasis(terms[j], theta_deg, direction);
    }
  }
  return std::sqrt(std::max(v, 0.0));
}

Result<HarmonicFit> FitHarmonicModel(const std::vector<FitPoint>& points,
                                     const std::vector<ErrorTerm>& terms) {
  const size_t m = points.size(), p = terms.size();
  if (p == 0) return MakeError("the error model has no terms");
  if (m < p) {
    return MakeError(fmt::format("fewer points ({}) than the model's {} parameters", m, p));
  }
  Eigen::MatrixXd a(m, p);  // sqrt(W) J
  Eigen::VectorXd b(m);     // sqrt(W) e
  for (size_t i = 0; i < m; ++i) {
    const FitPoint& pt = points[i];
    if (!(pt.u_deg > 0.0) || !std::isfinite(pt.u_deg) || !std::isfinite(pt.value_deg) ||
        !std::isfinite(pt.theta_deg)) {
      return MakeError(
          fmt::format("fit point {} has a non-finite value or a u that is not > 0", i));
    }
    for (size_t j = 0; j < p; ++j) {
      a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          ErrorTermBasis(terms[j], pt.theta_deg, pt.direction) / pt.u_deg;
    }
    b(static_cast<Eigen::Index>(i)) = pt.value_deg / pt.u_deg;
  }
  // Column scaling keeps theta [deg] and the unit harmonics on one footing for the rank test.
  Eigen::VectorXd scale = a.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < scale.size(); ++j) {
    if (!(scale(j) > 0.0)) scale(j) = 1.0;
  }
  const Eigen::MatrixXd as = a * scale.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(as);
  qr.setThreshold(1e-10);
  if (qr.rank() < static_cast<Eigen::Index>(p)) {
    return MakeError(
        "the reference angles cannot separate the error model's terms (singular design): "
        "collect plateaus at more, evenly spread table angles");
  }
  const Eigen::VectorXd beta = scale.cwiseInverse().asDiagonal() * qr.solve(b);
  const Eigen::MatrixXd normal = a.transpose() * a;  // J^T W J
  Eigen::MatrixXd cov = normal.ldlt().solve(
      Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(p)));

  HarmonicFit fit;
  fit.terms = terms;
  fit.params.assign(beta.data(), beta.data() + p);
  fit.dof = static_cast<int>(m - p);
  const Eigen::VectorXd weighted_residual = b - a * beta;
  fit.chi2 = weighted_residual.squaredNorm();
  fit.reduced_chi2 = fit.dof > 0 ? fit.chi2 / fit.dof : 0.0;
  if (fit.reduced_chi2 > 1.0) {
    cov *= fit.reduced_chi2;
    fit.covariance_scaled = true;
  }
  fit.covariance.assign(p, std::vector<double>(p, 0.0));
  for (size_t i = 0; i < p; ++i) {
    for (size_t j = 0; j < p; ++j) {
      fit.covariance[i][j] = cov(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
    fit.u.push_back(std::sqrt(std::max(fit.covariance[i][i], 0.0)));
  }
  double ss = 0.0;
  for (size_t i = 0; i < m; ++i) {
    const double r = points[i].value_deg - fit.Predict(points[i].theta_deg, points[i].direction);
    fit.residuals_deg.push_back(r);
    ss += r * r;
  }
  fit.residual_rms_deg = fit.dof > 0 ? std::sqrt(ss / fit.dof) : 0.0;
  return fit;
}

}  // namespace metro
