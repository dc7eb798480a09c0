// Nested model comparison of the calibration models (issue #36; model_selection.hpp).
#include "calibration/model_selection.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>

namespace metro::calibration_internal {

double ChiSquareUpperTail(double x, double dof) {
  if (!(dof > 0)) return 1.0;
  if (!(x > 0)) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), x));
}

namespace {

// "p = 0.012", or "p < 1e-16" below double's resolution of an upper tail.
std::string PText(double p) {
  return p < 1e-16 ? std::string("p < 1e-16") : fmt::format("p = {:.2g}", p);
}

bool FitsItsNoise(const LadderFit& f) {
  return f.chi2_dof <= 0 || ChiSquareUpperTail(f.chi2, f.chi2_dof) >= kGoodnessAlpha;
}

bool IsExact(const LadderFit& f) {
  return f.chi2_dof <= 0 || (f.orientations > 0 && f.orientations <= f.parameters);
}

}  // namespace

ModelComparison CompareModels(const LadderFit& smaller, const LadderFit& larger) {
  ModelComparison c;
  c.smaller = smaller.kind;
  c.larger = larger.kind;
  c.dof1 = static_cast<double>(larger.parameters - smaller.parameters);
  if (smaller.chi2 < 0 || larger.chi2 < 0) {
    c.note = "not computed: the residuals could not be measured against the noise of the data";
    return c;
  }
  if (!(c.dof1 > 0)) {
    c.note = "not computed: the larger model has no more free parameters";
    return c;
  }
  const double delta = std::max(0.0, smaller.chi2 - larger.chi2);
  if (FitsItsNoise(larger)) {
    // The larger model describes the data to its noise: the chi-square difference
    // ~ chi2(delta p) (a likelihood-ratio test with known noise).
    c.test = "chi2_difference";
    c.statistic = delta;
    c.p_value = ChiSquareUpperTail(delta, c.dof1);
  } else {
    // It does not: scaled by its own residual variance, F ~ F(delta p, dof_larger).
    c.test = "F";
    c.dof2 = larger.chi2_dof;
    c.statistic = (delta / c.dof1) / (larger.chi2 / larger.chi2_dof);
    c.p_value = c.statistic > 0 ? boost::math::cdf(boost::math::complement(
                                      boost::math::fisher_f(c.dof1, c.dof2), c.statistic))
                                : 1.0;
  }
  c.rejected = c.p_value < kComparisonAlpha;
  return c;
}

std::vector<ModelComparison> CompareLadder(const std::vector<LadderFit>& fits) {
  std::vector<ModelComparison> out;
  for (size_t i = 0; i + 1 < fits.size(); ++i) {
    const LadderFit& s = fits[i];
    const LadderFit& l = fits[i + 1];
    if (s.fitted && l.fitted) {
      out.push_back(CompareModels(s, l));
      continue;
    }
    ModelComparison c;
    c.smaller = s.kind;
    c.larger = l.kind;
    const LadderFit& missing = s.fitted ? l : s;
    c.note = fmt::format("not computed: the '{}' model could not be fitted: {}",
                         ModelKindName(missing.kind), missing.why);
    out.push_back(std::move(c));
  }
  return out;
}

ModelKind ChooseModel(const std::vector<LadderFit>& fits,
                      const std::vector<ModelComparison>& comparisons) {
  int at = -1;
  for (int i = static_cast<int>(fits.size()) - 1; i >= 0 && at < 0; --i) {
    if (fits[static_cast<size_t>(i)].fitted) at = i;
  }
  METRO_CHECK(at >= 0);
  while (at > 0) {
    const LadderFit& smaller = fits[static_cast<size_t>(at - 1)];
    const LadderFit& larger = fits[static_cast<size_t>(at)];
    const auto c = std::find_if(comparisons.begin(), comparisons.end(), [&](const auto& x) {
      return x.smaller == smaller.kind && x.larger == larger.kind;
    });
    if (!smaller.fitted || c == comparisons.end() || c->test.empty() || c->rejected) break;
    --at;
  }
  return fits[static_cast<size_t>(at)].kind;
}

CrossAxisTypeB DatasheetCrossAxis() {
  CrossAxisTypeB b;
  b.source =
      "MPU-6000/6050 product specification PS-MPU-6000A-00 rev 3.4: cross-axis sensitivity "
      "+-2 % (accelerometer and gyroscope)";
  b.half_width = 0.02;
  b.distribution = "rectangular";
  b.u = b.half_width / std::sqrt(3.0);
  return b;
}

ModelCheck CheckChosenModel(ImuSensor imu, const LadderFit& chosen, bool auto_selected,
                            std::vector<ModelComparison> comparisons, bool robust) {
  ModelCheck m;
  m.selection = auto_selected ? "auto" : "given";
  m.comparisons = std::move(comparisons);
  m.chi2 = chosen.chi2;
  m.chi2_dof = chosen.chi2_dof;
  const char* name = ModelKindName(chosen.kind);
  const char* sensor_name = ImuSensorLongName(imu);
  const bool exact = chosen.chi2 >= 0 && IsExact(chosen);
  if (chosen.chi2 >= 0 && chosen.chi2_dof > 0) {
    m.p_value = ChiSquareUpperTail(chosen.chi2, chosen.chi2_dof);
  }
  // A comparison against the next larger model that rejects the chosen one.
  const ModelComparison* against = nullptr;
  for (const ModelComparison& c : m.comparisons) {
    if (c.smaller == chosen.kind && !c.test.empty()) against = &c;
  }
  const bool rejected_by_comparison = against != nullptr && against->rejected;
  const bool rejected_by_noise = m.p_value >= 0 && m.p_value < kGoodnessAlpha;
  std::string evidence;
  if (exact) {
    m.status = "exact_fit";
    evidence = chosen.orientations > 0
                   ? fmt::format(
                         "the {} '{}' model has {} parameters for {} distinct "
                         "orientations: the fit is exact and nothing tests the model",
                         sensor_name, name, chosen.parameters, chosen.orientations)
                   : fmt::format(
                         "the {} '{}' model leaves no residual degrees of freedom: the "
                         "fit is exact and nothing tests the model",
                         sensor_name, name);
  } else if (chosen.chi2 < 0) {
    m.status = "not_tested";
    m.reason = robust ? "a robust loss gives no chi-square against the noise of the data: the "
                        "model was not tested (use the default loss to test it)"
                      : "the residuals could not be measured against the noise of the data "
                        "(poses without noise): the model was not tested";
    return m;
  } else if (rejected_by_noise || rejected_by_comparison) {
    m.status = "rejected";
    std::string parts;
    if (rejected_by_noise) {
      parts = fmt::format(
          "its residuals are {:.3g} times their noise (chi-square {:.4g} over "
          "{:.4g} dof, {})",
          std::sqrt(chosen.chi2 / chosen.chi2_dof), chosen.chi2, chosen.chi2_dof, PText(m.p_value));
    }
    if (rejected_by_comparison) {
      parts += fmt::format("{}the '{}' model fits significantly better ({} = {:.4g}, {})",
                           parts.empty() ? "" : "; ", ModelKindName(against->larger),
                           against->test == "F" ? "F" : "chi-square difference", against->statistic,
                           PText(against->p_value));
    }
    evidence = fmt::format("the data reject the {} '{}' model: {}", sensor_name, name, parts);
  } else {
    m.status = "accepted";
    return m;
  }
  switch (chosen.kind) {
    case ModelKind::kScale:
      m.type_b = DatasheetCrossAxis();
      m.reason = fmt::format(
          "{}; u includes a Type B term for the cross-axis sensitivity the model "
          "leaves out (+-{:g} %, rectangular, from the MPU-6050 datasheet) propagated to every "
          "constant. Record poses in more orientations (the corners and edges of a cube) and "
          "fit --model full or auto to determine the cross-axis terms instead",
          evidence, 100.0 * m.type_b->half_width);
      break;
    case ModelKind::kBias:
      m.model_rejected = true;
      m.reason = fmt::format(
          "{}; its u does not cover what the model leaves out, so the constants are "
          "marked model_rejected: fit --model scale, full or auto, or give "
          "--accept-rejected-model to use them anyway",
          evidence);
      break;
    case ModelKind::kFull:
      if (exact) {
        m.model_rejected = true;
        m.reason = fmt::format(
            "{} (u would rest on the noise alone), so the constants are marked "
            "model_rejected: record at least one more distinct orientation (the corners and "
            "edges of a cube), or give --accept-rejected-model to use them anyway",
            evidence);
      } else {
        m.reason =
            fmt::format("{}; no larger model is fitted, and u includes the misfit ({})", evidence,
                        imu == ImuSensor::kAccel
                            ? "a between-orientation component when the orientations disagree"
                            : "the covariance is scaled by the residuals' own scatter");
      }
      break;
  }
  return m;
}

}  // namespace metro::calibration_internal
