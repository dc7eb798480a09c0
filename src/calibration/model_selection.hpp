// Private: nested model comparison and the standing of the chosen model (issue #36;
// docs/calibration-model.md "Model selection"). The fits come from CalibrateTag's ladder
// bias < scale < full; these functions only compare and decide.
#pragma once

#include <string>
#include <vector>

#include "metro/calibration/calibrate.hpp"

namespace metro::calibration_internal {

// One model of a sensor's ladder, as fitted (or not).
struct LadderFit {
  ModelKind kind = ModelKind::kFull;
  bool fitted = false;
  std::string why;   // Why it could not be fitted (the fit's error message).
  double chi2 = -1;  // Against the noise (SensorSolution::chi2); -1 when not measured.
  double chi2_dof = 0;
  int parameters = 0;
  int orientations = 0;  // Accelerometer: distinct orientations; 0 when not counted.
};

// The significance levels: a smaller model is rejected against a larger one when p < 0.05;
// a model is rejected against its noise when p < 0.01 (the 99 % point the fit's warnings use).
inline constexpr double kComparisonAlpha = 0.05;
inline constexpr double kGoodnessAlpha = 0.01;

// The upper-tail probability of chi2(dof) at x (1 when dof <= 0).
double ChiSquareUpperTail(double x, double dof);

// `smaller` against `larger` (ModelComparison in calibrate.hpp for the tests).
ModelComparison CompareModels(const LadderFit& smaller, const LadderFit& larger);

// Each model of `fits` (in ladder order) against the next one; a pair with a model that was
// not fitted is listed with the reason in `note`.
std::vector<ModelComparison> CompareLadder(const std::vector<LadderFit>& fits);

// --model auto: from the largest fitted model down, the next smaller fitted one while the
// comparison between them accepts it. Precondition: some fit is fitted.
ModelKind ChooseModel(const std::vector<LadderFit>& fits,
                      const std::vector<ModelComparison>& comparisons);

// The standing of the chosen model (ModelCheck in calibrate.hpp): status, p-value, reason,
// model_rejected; `type_b` is set (without terms) when a Type B for the cross-axis terms the
// model leaves out is due (a rejected or exact scale model). `robust`: a robust loss (no
// chi-square against the noise).
ModelCheck CheckChosenModel(ImuSensor imu, const LadderFit& chosen, bool auto_selected,
                            std::vector<ModelComparison> comparisons, bool robust);

// The MPU-6000/6050 datasheet's cross-axis sensitivity, +-2 %, rectangular.
CrossAxisTypeB DatasheetCrossAxis();

}  // namespace metro::calibration_internal
