// EvaluateAccuracy runs these stages, in this order (the library stages they call:
// accuracy_stages.hpp; method: docs/accuracy.md):
//
//   tag            SelectTag, FindAngles        the tag, its window, the turned angle
//   reference      ReferenceAt, RawReferenceAt  the reference at each observation (aligned
//                                               log or table_angle_deg), unwrapped, pitch
//                                               fold check; the error series e_k
//   lag            ModelLag                     the response time and modelled transient
//   plateaus       FindPlateaus, WarnOnPlateaus plateaus and their settling warnings
//   errors, fit    ErrorsAndFit                 points, noise, curve, linearity,
//                                               hysteresis, repeatability
//   cross-axis     CrossAxes                    the other angles' coupling
//   budgets        ReadingBudgets, WarnOnBudgets single-reading U
#include "metro/accuracy/accuracy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "metro/accuracy/accuracy_stages.hpp"
#include "metro/core/angles.hpp"
#include "metro/stats/derived_quantity.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro {
namespace {

// Mean of an angle series over [begin, end) that may cross +-180 deg.
double AngleMean(const std::vector<double>& values, size_t begin, size_t end) {
  std::vector<double> v(values.begin() + static_cast<std::ptrdiff_t>(begin),
                        values.begin() + static_cast<std::ptrdiff_t>(end));
  UnwrapDegInPlace(&v);
  double sum = 0.0;
  for (double x : v) sum += x;
  return WrapDeg180(sum / static_cast<double>(v.size()));
}

// Unwraps a reference series with unknown (NaN) stretches: each known value is moved by a
// multiple of 360 deg to within 180 deg of the previous known one. True if anything moved.
bool UnwrapReference(std::vector<double>* ref) {
  bool moved = false;
  double previous = std::numeric_limits<double>::quiet_NaN();
  for (double& v : *ref) {
    if (std::isnan(v)) continue;
    if (!std::isnan(previous)) {
      const double u = previous + WrapDeg180(v - previous);
      moved = moved || std::fabs(u - v) > 1e-9;
      v = u;
    }
    previous = v;
  }
  return moved;
}

// The table angles in TableAxis order.
constexpr const char* kAxes[3] = {"yaw_deg", "pitch_deg", "roll_deg"};

// ---- tag ----------------------------------------------------------------------------------

// The tag (options.sensor, or the only one) and the window: a copy of the tag holding only the
// kept observations, in *windowed, when the window drops any. Sets result->sensor, ->window.
Result<const Tag*> SelectTag(const Session& session, const AccuracyOptions& options, Tag* windowed,
                             AccuracyResult* result) {
  const Tag* tag = nullptr;
  if (options.sensor == 0) {
    if (session.tags.size() != 1) {
      std::string list;
      for (const Tag& t : session.tags)
        list += (list.empty() ? "" : ", ") + std::to_string(t.sensor);
      return MakeError(session.path, 0,
                       "the session holds tags " + list + ": choose one with --sensor");
    }
    tag = &session.tags.front();
  } else {
    tag = session.FindTag(options.sensor);
    if (tag == nullptr) {
      return MakeError(session.path, 0,
                       fmt::format("the session has no tag {} (--sensor)", options.sensor));
    }
  }
  result->sensor = tag->sensor;
  result->window = ExplicitWindow(*tag, options.window);
  if (result->window.begin > 0 || result->window.end < result->window.n_total) {
    *windowed = *tag;
    windowed->KeepRows(result->window.begin, result->window.end);
    tag = windowed;
  }
  if (tag->size() == 0) {
    return MakeError(session.path, 0,
                     fmt::format("the window (--skip-samples, --skip-seconds, --from-s, --to-s) "
                                 "keeps no observation of tag {}",
                                 result->sensor));
  }
  result->window.t_first_s = tag->t_s.front();
  result->window.t_last_s = tag->t_s.back();
  return tag;
}

// The tag's three angles (kAxes order; nullptr where absent), the turned one and the others.
struct AngleColumns {
  const Quantity* angle[3] = {nullptr, nullptr, nullptr};
  int turned = 0;
  int others[2] = {0, 0};
  const Quantity& Turned() const { return *angle[turned]; }
};

// The turned axis is required; the two others only for the cross-axis coupling.
Result<AngleColumns> FindAngles(const Session& session, const Tag& tag,
                                const AccuracyOptions& options) {
  AngleColumns columns;
  for (int a = 0; a < 3; ++a) columns.angle[a] = tag.Find(kAxes[a]);
  const int turned = static_cast<int>(options.axis);
  columns.turned = turned;
  if (columns.angle[turned] == nullptr) {
    const std::optional<std::string> gap = MissingDerivationInputs(tag, kAxes[turned]);
    return MakeError(session.path, 0,
                     fmt::format("tag {} has no {} ({}): the accuracy evaluation of the {} table "
                                 "needs the tag's {}",
                                 tag.sensor, kAxes[turned],
                                 gap ? *gap : "nor a quaternion qw..qz to derive it from",
                                 TableAxisName(options.axis), kAxes[turned]));
  }
  for (int a = 0, j = 0; a < 3; ++a) {
    if (a != turned) columns.others[j++] = a;
  }
  return columns;
}

// ---- reference ----------------------------------------------------------------------------

// The reference at each tag observation: the separate log aligned to the tag (sets
// result->alignment), or the tag's own table_angle_deg.
Result<std::vector<double>> RawReferenceAt(const Session& session, const Session* reference,
                                           const Tag& tag, const std::vector<double>& tag_angle,
                                           const AccuracyOptions& options, AccuracyResult* result) {
  if (reference == nullptr) {
    const Quantity* table = tag.Find("table_angle_deg");
    if (table == nullptr) {
      return MakeError(session.path, 0,
                       fmt::format("tag {} has no table_angle_deg column: log the table's angle "
                                   "in session.csv or give a separate reference log with "
                                   "--reference",
                                   tag.sensor));
    }
    return table->values;
  }
  const Tag* ref_tag = nullptr;
  for (const Tag& t : reference->tags) {
    if (t.Find("table_angle_deg") != nullptr) {
      ref_tag = &t;
      break;
    }
  }
  if (ref_tag == nullptr) {
    return MakeError(reference->path, 0,
                     "the reference log has no table_angle_deg column: it needs t_s and "
                     "table_angle_deg");
  }
  if (tag.Find("table_angle_deg") != nullptr) {
    result->warnings.push_back(
        "the session has its own table_angle_deg; the separate reference log is used instead");
  }
  AlignmentOptions alignment = options.alignment;
  alignment.model_lag = alignment.model_lag && options.model_lag && !options.lag_tau_s;
  auto aligned = AlignReference(tag.t_s, tag_angle, ref_tag->t_s,
                                ref_tag->Find("table_angle_deg")->values, alignment);
  if (!aligned.ok()) {
    Error e = aligned.error();
    e.file = reference->path;
    return e;
  }
  result->separate_reference = true;
  result->alignment = std::move(aligned).value();
  return result->alignment->reference_deg;
}

// The reference, unwrapped, and checked against the pitch's fold at +-90 deg.
Result<std::vector<double>> ReferenceAt(const Session& session, const Session* reference,
                                        const Tag& tag, const std::vector<double>& tag_angle,
                                        const AccuracyOptions& options, AccuracyResult* result) {
  Result<std::vector<double>> raw =
      RawReferenceAt(session, reference, tag, tag_angle, options, result);
  if (!raw.ok()) return raw.error();
  std::vector<double> ref = std::move(raw).value();
  // A readout that wraps (e.g. at +-180 deg) is unwrapped, so that directions of travel,
  // sweeps and angle groups follow the table's motion.
  result->reference_unwrapped = UnwrapReference(&ref);
  if (options.axis == TableAxis::kPitch) {
    double worst = 0.0;
    for (double v : ref) {
      if (!std::isnan(v)) worst = std::max(worst, std::fabs(WrapDeg180(v)));
    }
    if (worst >= kGimbalLockWarnPitchDeg) {
      return MakeError(
          result->separate_reference ? reference->path : session.path, 0,
          fmt::format("the pitch table reaches {:.4g} deg: the tag's pitch is an Euler angle in "
                      "[-90, 90] deg that folds over at +-90 (yaw and roll flip by 180 deg), so "
                      "errors past {} deg cannot be evaluated; keep a pitch sweep within +-{} "
                      "deg, or mount the tag so that the table turns its yaw or roll",
                      worst, kGimbalLockWarnPitchDeg, kGimbalLockWarnPitchDeg));
    }
  }
  return ref;
}

// ---- lag ----------------------------------------------------------------------------------

// The tag's response time (result->lag_tau_s, ->lag_method), and the modelled lag behind the
// reference for settling at each plateau's start, when the lag is modelled.
std::optional<std::vector<double>> ModelLag(const Tag& tag, const std::vector<double>& tag_angle,
                                            const std::vector<double>& ref,
                                            const AccuracyOptions& options,
                                            AccuracyResult* result) {
  if (options.lag_tau_s) {
    result->lag_tau_s = *options.lag_tau_s;
    result->lag_method = "given";
  } else if (!options.model_lag) {
    result->lag_method = "not modelled (plateaus settle by settle_s alone)";
  } else if (result->alignment && result->alignment->lag_modelled) {
    result->lag_tau_s = result->alignment->lag_tau_s;
    result->lag_method = "estimated with the reference log's clock offset";
  } else {
    const LagEstimate lag = EstimateLag(tag.t_s, tag_angle, ref);
    result->lag_tau_s = lag.tau_s;
    result->lag_method = "estimated: the first-order response that best follows the reference";
    if (lag.at_limit) {
      result->warnings.push_back(fmt::format(
          "the tag's response time reached the searched limit ({} s): it may lag more", lag.tau_s));
    }
  }
  if (options.model_lag || options.lag_tau_s) {
    return ResponseTransient(tag.t_s, ref, result->lag_tau_s);
  }
  return std::nullopt;
}

// ---- plateaus -----------------------------------------------------------------------------

// The settling and trimming counts of result->segmentation, and the warnings they call for.
void WarnOnPlateaus(const AccuracyOptions& options, AccuracyResult* result) {
  int settle_at_limit = 0;
  for (const Plateau& p : result->segmentation.plateaus) {
    if (p.settle_at_limit) ++settle_at_limit;
    if (p.settled_by_lag) ++result->lag_settled_plateaus;
    result->max_settle_s = std::max(result->max_settle_s, p.t_start_s - p.t_rest_s);
  }
  if (settle_at_limit > 0) {
    result->warnings.push_back(fmt::format(
        "{} of {} plateaus: MSER-5 settling reached half the plateau; the tag may not have "
        "settled there (dwell longer, or set --settle-s)",
        settle_at_limit, result->segmentation.plateaus.size()));
  }
  if (result->lag_settled_plateaus > 0) {
    result->warnings.push_back(fmt::format(
        "the tag lags the table (first-order response time {:.3g} s): {} plateau start(s) "
        "trimmed beyond --settle-s until the modelled lag was within {} deg (up to {:.3g} s "
        "dropped)",
        result->lag_tau_s, result->lag_settled_plateaus, options.plateaus.settle_lag_residual_deg,
        result->max_settle_s));
  }
  const Segmentation& seg_done = result->segmentation;
  if (seg_done.departure_trimmed_plateaus > 0) {
    result->warnings.push_back(fmt::format(
        "the tag moved while the reference was still: {} of {} plateaus had a departing start "
        "or end trimmed ({} observations; the longest trimmed end {:.3g} s){}",
        seg_done.departure_trimmed_plateaus, seg_done.plateaus.size(),
        seg_done.departure_trimmed_samples, seg_done.max_end_trimmed_s,
        result->separate_reference ? "; check the reference clock offset (--reference-offset-s)"
                                   : ""));
  }
  if (seg_done.departure_kept_plateaus > 0) {
    result->warnings.push_back(fmt::format(
        "{} plateau(s): the tag's error drifts away from the plateau's level over more than {} "
        "% of the plateau; kept (drift, not motion), it widens the plateau's u",
        seg_done.departure_kept_plateaus, 100.0 * options.plateaus.max_departure_fraction));
  }
  for (const ExcludedSpan& e : result->segmentation.excluded) {
    if (e.reason == "too short after settling" && result->lag_tau_s > 0.0) {
      result->warnings.push_back(
          "plateaus too short to settle were excluded (see segmentation.excluded): dwell "
          "longer than the settling the tag's lag needs");
      break;
    }
  }
}

// ---- errors, fit, linearity, hysteresis, repeatability --------------------------------------

Status ErrorsAndFit(const Session& session, const std::vector<double>& error,
                    const AccuracyOptions& options, AccuracyResult* result) {
  result->noise = PlateauNoiseOf(error, result->segmentation.plateaus);
  result->points =
      PlateauErrors(error, result->segmentation, result->noise, options.resolution_deg);
  result->reading_std_deg = result->noise.sigma_deg;
  result->reading_dof = result->noise.dof;
  result->systematic = SystematicErrorOf(result->points);

  auto curve = FitErrorCurve(result->points, options.model, options.angle_match_deg);
  if (!curve.ok()) {
    Error e = curve.error();
    if (e.file.empty()) e.file = session.path;
    return e;
  }
  result->model = curve.value().model;
  result->fit = std::move(curve.value().fit);
  result->fit_hysteresis_term = curve.value().hysteresis_term;
  result->max_prediction_u_deg = curve.value().max_prediction_u_deg;

  result->linearity = LinearityOf(result->points, options.angle_match_deg);
  result->hysteresis = HysteresisOf(result->points, options.angle_match_deg);
  result->repeatability = RepeatabilityOf(result->points, options.angle_match_deg);
  if (!result->hysteresis.available) {
    result->warnings.push_back(fmt::format(
        "hysteresis was not measured (no angle visited both turning up and turning down): the "
        "corrected U assumes up to {} deg (--assumed-hysteresis-deg); sweep up and back down "
        "to measure it",
        options.assumed_hysteresis_deg));
  }
  return Status::Ok();
}

// ---- cross-axis ---------------------------------------------------------------------------

// The other two angles' plateau means and u (set in result->points) and their coupling.
void CrossAxes(const AngleColumns& columns, const AccuracyOptions& options,
               AccuracyResult* result) {
  const int* others = columns.others;
  for (int j = 0; j < 2; ++j) result->cross_axis[j].quantity = kAxes[others[j]];
  if (columns.angle[others[0]] == nullptr || columns.angle[others[1]] == nullptr) {
    result->cross_axis_available = false;
    result->cross_axis_note = fmt::format(
        "the session has the tag's {} only: cross-axis coupling ({} and {}) is not evaluated",
        kAxes[columns.turned], kAxes[others[0]], kAxes[others[1]]);
    result->warnings.push_back(result->cross_axis_note);
    return;
  }
  for (int j = 0; j < 2; ++j) {
    const std::vector<double>& v = columns.angle[others[j]]->values;
    const PlateauNoise noise = PlateauNoiseOf(v, result->segmentation.plateaus);
    std::vector<double> means, us;
    for (AccuracyPoint& pt : result->points) {
      const Plateau& p = result->segmentation.plateaus[pt.index];
      pt.other_mean_deg[j] = AngleMean(v, p.begin, p.end);
      pt.other_u_deg[j] =
          std::max(noise.sigma_deg * std::sqrt(Ar1MeanVarianceFactor(p.n(), noise.phi)),
                   options.resolution_deg / std::sqrt(12.0 * static_cast<double>(p.n())));
      means.push_back(pt.other_mean_deg[j]);
      us.push_back(pt.other_u_deg[j]);
    }
    result->cross_axis[j] =
        CrossAxisOf(kAxes[others[j]], result->points, means, us, options.angle_match_deg);
  }
}

// ---- budgets ------------------------------------------------------------------------------

// The warnings that follow ReadingBudgets.
void WarnOnBudgets(const AccuracyOptions& options, AccuracyResult* result) {
  if (options.reference.u_deg == 0.0) {
    result->warnings.push_back(
        "no reference uncertainty given: the table is treated as exact (--reference-u DEG)");
  }
  if (result->fit.covariance_scaled) {
    result->warnings.push_back(fmt::format(
        "the plateau errors scatter about the curve {:.3g} times more (in variance) than their "
        "Type A u allow; the fit covariance is scaled by the reduced chi-square",
        result->fit.reduced_chi2));
  }
}

}  // namespace

Result<ReferenceUncertainty> ReferenceUncertaintyFromBudget(const std::string& path) {
  auto budget = LoadBudget(path);
  if (!budget.ok()) return budget.error();
  const Budget& b = budget.value();
  if (!b.unit.empty() && b.unit != "deg") {
    return MakeError(path, 0,
                     "the reference budget's measurand is in '" + b.unit +
                         "'; the table's uncertainty must be in deg");
  }
  auto gum = EvaluateGum(b);
  if (!gum.ok()) return gum.error();
  ReferenceUncertainty r;
  r.u_deg = gum.value().u;
  r.dof = gum.value().dof_eff;
  r.source = path;
  return r;
}

bool AccuracyOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (sensor < 0 || sensor > 255) return fail(fmt::format("sensor {} is not in 1..255", sensor));
  if (!plateaus.IsValid(why)) return false;
  if (!type_a.IsValid(why)) return false;
  if (!alignment.IsValid(why)) return false;
  if (!window.IsValid(why)) return false;
  if (window.settle_auto) {
    return fail("window.settle_auto does not apply here: plateaus settle by plateaus.settle_auto");
  }
  if (!(angle_match_deg > 0.0) || !std::isfinite(angle_match_deg)) {
    return fail("angle_match_deg must be > 0");
  }
  if (!(reference.u_deg >= 0.0) || !std::isfinite(reference.u_deg)) {
    return fail(fmt::format("the reference's standard uncertainty must be >= 0 deg, got {}",
                            reference.u_deg));
  }
  if (!(reference.dof > 0.0)) return fail("the reference's degrees of freedom must be > 0");
  if (!(resolution_deg >= 0.0) || !std::isfinite(resolution_deg)) {
    return fail("resolution_deg must be >= 0");
  }
  if (!(coverage > 0.0 && coverage < 1.0)) return fail("coverage must be in (0, 1)");
  if (!(assumed_hysteresis_deg >= 0.0) || !std::isfinite(assumed_hysteresis_deg)) {
    return fail("assumed_hysteresis_deg must be >= 0");
  }
  if (lag_tau_s && (!(*lag_tau_s >= 0.0) || !std::isfinite(*lag_tau_s))) {
    return fail("the tag's response time lag_tau_s must be >= 0 s");
  }
  return true;
}

Result<AccuracyResult> EvaluateAccuracy(const Session& session, const Session* reference,
                                        const AccuracyOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  AccuracyResult result;
  result.options = options;
  result.axis = options.axis;
  result.quantity = TableAxisQuantity(options.axis);

  Tag windowed;
  Result<const Tag*> selected = SelectTag(session, options, &windowed, &result);
  if (!selected.ok()) return selected.error();
  const Tag& tag = *selected.value();
  Result<AngleColumns> angles = FindAngles(session, tag, options);
  if (!angles.ok()) return angles.error();
  const std::vector<double>& tag_angle = angles.value().Turned().values;

  Result<std::vector<double>> ref =
      ReferenceAt(session, reference, tag, tag_angle, options, &result);
  if (!ref.ok()) return ref.error();
  std::vector<double> error(tag_angle.size());
  for (size_t k = 0; k < error.size(); ++k) {
    error[k] =
        std::isnan(ref.value()[k]) ? ref.value()[k] : WrapDeg180(tag_angle[k] - ref.value()[k]);
  }
  const std::optional<std::vector<double>> transient =
      ModelLag(tag, tag_angle, ref.value(), options, &result);

  // Stage: plateaus.
  auto seg = FindPlateaus(tag.t_s, ref.value(), error, options.plateaus,
                          transient ? &*transient : nullptr);
  if (!seg.ok()) {
    Error e = seg.error();
    e.file = result.separate_reference ? reference->path : session.path;
    return e;
  }
  result.segmentation = std::move(seg).value();
  WarnOnPlateaus(options, &result);

  // Stages: errors, fit, linearity, hysteresis, repeatability, cross-axis, budgets.
  if (Status s = ErrorsAndFit(session, error, options, &result); !s.ok()) return s.error();
  CrossAxes(angles.value(), options, &result);
  if (Status s = ReadingBudgets(options, &result); !s.ok()) return s.error();
  WarnOnBudgets(options, &result);
  return result;
}

}  // namespace metro
