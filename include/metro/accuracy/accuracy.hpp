// Accuracy of a tag against a rotation-table reference (issue #8; method and formulas in
// docs/accuracy.md, report layout "metro.accuracy-report/1" in accuracy_report.hpp).
//
// Input: a session with the tag's angles (yaw/pitch/roll_deg, read or derived from the
// quaternion) and either its own `table_angle_deg` column or a separate reference log
// (t_s, table_angle_deg) aligned on t_s (alignment.hpp). The table turns `axis`.
//
//  1. Plateaus of the reference (plateaus.hpp); motion and settling excluded.
//  2. Per plateau i: reference theta_i, error series e_k = WrapDeg180(tag_k - theta_i)
//     (unwrapped as a series), Type A of the error (JCGM 100 4.2 with Zhang's n_eff,
//     stats/type_a.hpp): e_i = mean, u_i = s(e_bar) autocorrelation-aware, nu_i = n_eff - 1;
//     tag mean = WrapDeg180(theta_i + e_i).
//  3. Over the sweep: systematic error (mean, RMS, max |e_i|), the weighted error curve
//     (error_fit.hpp, weights 1/u_i^2), linearity (deviation of the per-angle mean errors
//     from their least-squares straight line), hysteresis (up minus down at each angle
//     visited both ways), repeatability (ISO 5725-2 pooled s_r of plateau errors at the same
//     angle and direction across sweeps), cross-axis coupling (the two axes not turned: per
//     plateau means, c0 + a1 cos + b1 sin fitted when the coverage allows).
//  4. Uncertainty of a single tag reading (JCGM 100 5.1.2 and G.4.1 through the uncertainty
//     module's GUM evaluator, every sensitivity 1): after correction by the curve
//     {reading noise, fit prediction, fit residual, reference, resolution}; without
//     correction {systematic error (RMS), reading noise, reference, resolution}; plus the
//     F.2.4.5-style bound U(random) + max |e_i|.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "metro/accuracy/alignment.hpp"
#include "metro/accuracy/error_fit.hpp"
#include "metro/accuracy/plateaus.hpp"
#include "metro/accuracy/table_axis.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/stats/session_type_a.hpp"
#include "metro/stats/type_a.hpp"
#include "metro/uncertainty/gum.hpp"

namespace metro {

// The reference's (table's) standard uncertainty from its certificate.
struct ReferenceUncertainty {
  double u_deg = 0.0;
  double dof = std::numeric_limits<double>::infinity();
  std::string source = "not given";  // "--reference-u", or the budget file.
};

// Evaluates a budget file (docs/budget-format.md) describing the reference's error with the
// GUM framework: u = u_c, dof = nu_eff. The measurand's unit must be "deg" (or empty).
Result<ReferenceUncertainty> ReferenceUncertaintyFromBudget(const std::string& path);

struct AccuracyOptions {
  TableAxis axis = TableAxis::kYaw;
  int sensor = 0;  // 0: the session's only tag.
  PlateauOptions plateaus;
  TypeAOptions type_a;
  ErrorModel model = ErrorModel::kAuto;
  double angle_match_deg = 0.05;  // Reference angles closer than this are the same angle.
  ReferenceUncertainty reference;
  // The hysteresis a reading may carry when the sweep never visited an angle both ways (the
  // corrected U then adds a rectangular input of this half-width, and says so).
  double assumed_hysteresis_deg = 0.2;
  // The tag's first-order response time: estimated from the motion (false: not modelled, the
  // plateaus settle by settle_s alone); a given value is used as is.
  bool model_lag = true;
  std::optional<double> lag_tau_s;
  double resolution_deg = 0.01;  // The packets' quantisation step.
  double coverage = 0.95;
  AlignmentOptions alignment;  // With a separate reference log.
  // The part of the tag's record evaluated (--skip-samples, --skip-seconds, --from-s,
  // --to-s); settle_auto is not used here: plateaus settle by PlateauOptions.
  WindowOptions window;

  bool IsValid(std::string* why) const;
};

struct PlateauTypeA {
  int64_t n = 0;
  double std_deg = 0.0;  // s of one reading.
  double u_deg = 0.0;    // s(mean), autocorrelation-aware (floored, see docs).
  double n_eff = 0.0;
  double dof = 0.0;  // n_eff - 1
};

struct AccuracyPoint {
  size_t index = 0;
  double reference_deg = 0.0;
  double mean_deg = 0.0;   // Tag mean, wrapped into (-180, 180].
  double error_deg = 0.0;  // Tag minus reference.
  PlateauTypeA type_a;
  int direction = 0;  // +1 approached turning up, -1 turning down, 0 first plateau.
  int sweep = 0;      // 1-based: a new sweep starts at each up-turn after a down pass.
  double t_start_s = 0.0, t_end_s = 0.0;
  size_t settle_samples = 0;
  double other_mean_deg[2] = {0.0, 0.0};  // The two axes not turned (yaw, pitch, roll order).
  double other_u_deg[2] = {0.0, 0.0};     // Their u (the same AR(1) method as the error).
};

// The tag's reading noise on the plateaus (accuracy_stages.hpp, PlateauNoiseOf).
struct PlateauNoise {
  double sigma_deg = 0.0;
  double phi = 0.0;  // Lag-1 correlation per observation, in [0, 0.999].
  double dof = 0.0;  // sigma^2's degrees of freedom.
  size_t plateaus = 0;
};

struct SystematicError {
  double mean_deg = 0.0;          // Mean of the plateau errors.
  double std_deg = 0.0;           // Their standard deviation (spread over the range).
  double rms_deg = 0.0;           // sqrt(mean e_i^2), about zero.
  double max_abs_deg = 0.0;       // max |e_i|.
  double at_reference_deg = 0.0;  // Where max |e_i| occurs.
};

struct Linearity {
  double max_abs_deviation_deg = 0.0;
  double at_reference_deg = 0.0;
  double rms_deviation_deg = 0.0;
  double percent_of_span = 0.0;  // 100 max |dev| / span.
  double line_offset_deg = 0.0;  // The least-squares straight line through the angle means.
  double line_slope = 0.0;
  size_t angles = 0;
  // u of the deviation at at_reference_deg: d = (I - H) m over the per-angle means m with
  // their u (JCGM 100 5.1.2 for the linear map; H the straight line's hat matrix).
  double u_max_abs_deviation_deg = 0.0;
};

struct HysteresisPair {
  double reference_deg = 0.0;
  double up_error_deg = 0.0;
  double down_error_deg = 0.0;
  double hysteresis_deg = 0.0;  // up - down
  double u_deg = 0.0;
  double dof = 0.0;
  int up_count = 0, down_count = 0;
};

struct Hysteresis {
  std::vector<HysteresisPair> pairs;
  bool available = false;
  double mean_deg = 0.0;  // Inverse-variance weighted mean of the pairs.
  double u_mean_deg = 0.0;
  double max_abs_deg = 0.0;
  double u_max_abs_deg = 0.0;  // u of the pair with the largest |h|.
  double at_reference_deg = 0.0;
  std::string note;
};

struct Repeatability {
  bool available = false;
  double s_r_deg = 0.0;    // Pooled repeatability standard deviation.
  double dof = 0.0;        // sum (m_j - 1)
  double u_s_r_deg = 0.0;  // s_r / sqrt(2 dof) (JCGM 100 E.4.3).
  int groups = 0;          // (angle, direction) groups with >= 2 plateaus.
  int sweeps = 0;
  std::string note;
};

struct CrossAxis {
  std::string quantity;  // e.g. "pitch_deg"
  double mean_deg = 0.0;
  double span_deg = 0.0;  // max - min of the plateau means.
  bool fitted = false;    // c0 + a1 cos + b1 sin
  HarmonicFit fit;
  double amplitude_deg = 0.0;  // sqrt(a1^2 + b1^2)
  double u_amplitude_deg = 0.0;
};

struct ReadingBudget {
  std::string name;  // "corrected", "uncorrected"
  GumResult gum;
  std::vector<std::string> notes;        // How each input's u was formed, per input.
  std::vector<std::string> input_names;  // The inputs' names, in the order of `notes`.
};

struct AccuracyResult {
  TableAxis axis = TableAxis::kYaw;
  int sensor = 0;
  std::string quantity;  // e.g. "yaw_deg"
  bool separate_reference = false;
  AppliedWindow window;  // n_total, begin, end, t_first_s, t_last_s of the tag's record.
  std::optional<Alignment> alignment;
  Segmentation segmentation;
  std::vector<AccuracyPoint> points;
  SystematicError systematic;
  ErrorModel model = ErrorModel::kLinear;
  HarmonicFit fit;
  bool fit_hysteresis_term = false;  // The curve has the h d / 2 term.
  PlateauNoise noise;                // Reading noise (the error's AR(1) over the plateaus).
  double lag_tau_s = 0.0;            // The tag's response time used for settling.
  std::string lag_method;            // "estimated ...", "given", "not modelled".
  int lag_settled_plateaus = 0;      // Plateaus whose start was trimmed by the lag rule.
  double max_settle_s = 0.0;         // The longest settling dropped at a plateau's start.
  bool reference_unwrapped = false;  // The readout wrapped and was unwrapped.
  bool cross_axis_available = true;  // The session has the two other angles.
  std::string cross_axis_note;
  double max_prediction_u_deg = 0.0;  // max over the points of u_fit(theta_i)
  Linearity linearity;
  Hysteresis hysteresis;
  Repeatability repeatability;
  CrossAxis cross_axis[2];
  double reading_std_deg = 0.0;  // Pooled s of one reading over the plateaus.
  double reading_dof = 0.0;
  ReadingBudget corrected;
  ReadingBudget uncorrected;
  double random_expanded_deg = 0.0;               // U of {reading noise, reference, resolution}
  double uncorrected_max_abs_expanded_deg = 0.0;  // random U + max |e_i|
  double uncorrected_gum_expanded_deg = 0.0;      // k u_c of the uncorrected budget.
  std::string which_u;                            // Which U to quote, and why.
  std::vector<std::string> warnings;
  AccuracyOptions options;
};

// `reference`: a separate reference log (t_s, table_angle_deg), or nullptr when `session`
// has its own table_angle_deg column. Every error is about the input or options (what to
// collect): no such tag or several tags without a choice, no tag angles, no reference
// column, logs that do not overlap, no plateau, fewer points than the error model needs.
Result<AccuracyResult> EvaluateAccuracy(const Session& session, const Session* reference,
                                        const AccuracyOptions& options);

}  // namespace metro
