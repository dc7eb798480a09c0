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

  // The tag.
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
  result.sensor = tag->sensor;
  // The window: a copy of the tag holding only the kept observations.
  result.window = ExplicitWindow(*tag, options.window);
  Tag windowed;
  if (result.window.begin > 0 || result.window.end < result.window.n_total) {
    windowed = *tag;
    windowed.KeepRows(result.window.begin, result.window.end);
    tag = &windowed;
  }
  if (tag->size() == 0) {
    return MakeError(session.path, 0,
                     fmt::format("the window (--skip-samples, --skip-seconds, --from-s, --to-s) "
                                 "keeps no observation of tag {}",
                                 result.sensor));
  }
  result.window.t_first_s = tag->t_s.front();
  result.window.t_last_s = tag->t_s.back();
  // The turned axis is required; the two others only for the cross-axis coupling.
  const char* const kAxes[3] = {"yaw_deg", "pitch_deg", "roll_deg"};
  const Quantity* angle[3];
  for (int a = 0; a < 3; ++a) angle[a] = tag->Find(kAxes[a]);
  const int turned = static_cast<int>(options.axis);
  if (angle[turned] == nullptr) {
    const std::optional<std::string> gap = MissingDerivationInputs(*tag, kAxes[turned]);
    return MakeError(session.path, 0,
                     fmt::format("tag {} has no {} ({}): the accuracy evaluation of the {} table "
                                 "needs the tag's {}",
                                 tag->sensor, kAxes[turned],
                                 gap ? *gap : "nor a quaternion qw..qz to derive it from",
                                 TableAxisName(options.axis), kAxes[turned]));
  }
  int others[2];
  for (int a = 0, j = 0; a < 3; ++a) {
    if (a != turned) others[j++] = a;
  }
  const std::vector<double>& tag_angle = angle[turned]->values;

  // The reference at each tag observation.
  std::vector<double> ref;
  if (reference != nullptr) {
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
    if (tag->Find("table_angle_deg") != nullptr) {
      result.warnings.push_back(
          "the session has its own table_angle_deg; the separate reference log is used instead");
    }
    AlignmentOptions alignment = options.alignment;
    alignment.model_lag = alignment.model_lag && options.model_lag && !options.lag_tau_s;
    auto aligned = AlignReference(tag->t_s, tag_angle, ref_tag->t_s,
                                  ref_tag->Find("table_angle_deg")->values, alignment);
    if (!aligned.ok()) {
      Error e = aligned.error();
      e.file = reference->path;
      return e;
    }
    result.separate_reference = true;
    result.alignment = std::move(aligned).value();
    ref = result.alignment->reference_deg;
  } else {
    const Quantity* table = tag->Find("table_angle_deg");
    if (table == nullptr) {
      return MakeError(session.path, 0,
                       fmt::format("tag {} has no table_angle_deg column: log the table's angle "
                                   "in session.csv or give a separate reference log with "
                                   "--reference",
                                   tag->sensor));
    }
    ref = table->values;
  }
  // A readout that wraps (e.g. at +-180 deg) is unwrapped, so that directions of travel,
  // sweeps and angle groups follow the table's motion.
  result.reference_unwrapped = UnwrapReference(&ref);
  if (options.axis == TableAxis::kPitch) {
    double worst = 0.0;
    for (double v : ref) {
      if (!std::isnan(v)) worst = std::max(worst, std::fabs(WrapDeg180(v)));
    }
    if (worst >= kGimbalLockWarnPitchDeg) {
      return MakeError(
          result.separate_reference ? reference->path : session.path, 0,
          fmt::format("the pitch table reaches {:.4g} deg: the tag's pitch is an Euler angle in "
                      "[-90, 90] deg that folds over at +-90 (yaw and roll flip by 180 deg), so "
                      "errors past {} deg cannot be evaluated; keep a pitch sweep within +-{} "
                      "deg, or mount the tag so that the table turns its yaw or roll",
                      worst, kGimbalLockWarnPitchDeg, kGimbalLockWarnPitchDeg));
    }
  }
  std::vector<double> error(tag_angle.size());
  for (size_t k = 0; k < error.size(); ++k) {
    error[k] = std::isnan(ref[k]) ? ref[k] : WrapDeg180(tag_angle[k] - ref[k]);
  }

  // The tag's response time, for settling at each plateau's start.
  if (options.lag_tau_s) {
    result.lag_tau_s = *options.lag_tau_s;
    result.lag_method = "given";
  } else if (!options.model_lag) {
    result.lag_method = "not modelled (plateaus settle by settle_s alone)";
  } else if (result.alignment && result.alignment->lag_modelled) {
    result.lag_tau_s = result.alignment->lag_tau_s;
    result.lag_method = "estimated with the reference log's clock offset";
  } else {
    const LagEstimate lag = EstimateLag(tag->t_s, tag_angle, ref);
    result.lag_tau_s = lag.tau_s;
    result.lag_method = "estimated: the first-order response that best follows the reference";
    if (lag.at_limit) {
      result.warnings.push_back(fmt::format(
          "the tag's response time reached the searched limit ({} s): it may lag more", lag.tau_s));
    }
  }
  std::optional<std::vector<double>> transient;
  if (options.model_lag || options.lag_tau_s) {
    transient = ResponseTransient(tag->t_s, ref, result.lag_tau_s);
  }

  // Stage: plateaus.
  auto seg =
      FindPlateaus(tag->t_s, ref, error, options.plateaus, transient ? &*transient : nullptr);
  if (!seg.ok()) {
    Error e = seg.error();
    e.file = result.separate_reference ? reference->path : session.path;
    return e;
  }
  result.segmentation = std::move(seg).value();
  int settle_at_limit = 0;
  for (const Plateau& p : result.segmentation.plateaus) {
    if (p.settle_at_limit) ++settle_at_limit;
    if (p.settled_by_lag) ++result.lag_settled_plateaus;
    result.max_settle_s = std::max(result.max_settle_s, p.t_start_s - p.t_rest_s);
  }
  if (settle_at_limit > 0) {
    result.warnings.push_back(fmt::format(
        "{} of {} plateaus: MSER-5 settling reached half the plateau; the tag may not have "
        "settled there (dwell longer, or set --settle-s)",
        settle_at_limit, result.segmentation.plateaus.size()));
  }
  if (result.lag_settled_plateaus > 0) {
    result.warnings.push_back(fmt::format(
        "the tag lags the table (first-order response time {:.3g} s): {} plateau start(s) "
        "trimmed beyond --settle-s until the modelled lag was within {} deg (up to {:.3g} s "
        "dropped)",
        result.lag_tau_s, result.lag_settled_plateaus, options.plateaus.settle_lag_residual_deg,
        result.max_settle_s));
  }
  const Segmentation& seg_done = result.segmentation;
  if (seg_done.departure_trimmed_plateaus > 0) {
    result.warnings.push_back(fmt::format(
        "the tag moved while the reference was still: {} of {} plateaus had a departing start "
        "or end trimmed ({} observations; the longest trimmed end {:.3g} s){}",
        seg_done.departure_trimmed_plateaus, seg_done.plateaus.size(),
        seg_done.departure_trimmed_samples, seg_done.max_end_trimmed_s,
        result.separate_reference ? "; check the reference clock offset (--reference-offset-s)"
                                  : ""));
  }
  if (seg_done.departure_kept_plateaus > 0) {
    result.warnings.push_back(fmt::format(
        "{} plateau(s): the tag's error drifts away from the plateau's level over more than {} "
        "% of the plateau; kept (drift, not motion), it widens the plateau's u",
        seg_done.departure_kept_plateaus, 100.0 * options.plateaus.max_departure_fraction));
  }
  for (const ExcludedSpan& e : result.segmentation.excluded) {
    if (e.reason == "too short after settling" && result.lag_tau_s > 0.0) {
      result.warnings.push_back(
          "plateaus too short to settle were excluded (see segmentation.excluded): dwell "
          "longer than the settling the tag's lag needs");
      break;
    }
  }

  // Stage: errors.
  result.noise = PlateauNoiseOf(error, result.segmentation.plateaus);
  result.points = PlateauErrors(error, result.segmentation, result.noise, options.resolution_deg);
  result.reading_std_deg = result.noise.sigma_deg;
  result.reading_dof = result.noise.dof;
  result.systematic = SystematicErrorOf(result.points);

  // Stage: fit.
  auto curve = FitErrorCurve(result.points, options.model, options.angle_match_deg);
  if (!curve.ok()) {
    Error e = curve.error();
    if (e.file.empty()) e.file = session.path;
    return e;
  }
  result.model = curve.value().model;
  result.fit = std::move(curve.value().fit);
  result.fit_hysteresis_term = curve.value().hysteresis_term;
  result.max_prediction_u_deg = curve.value().max_prediction_u_deg;

  // Stages: linearity, hysteresis, repeatability.
  result.linearity = LinearityOf(result.points, options.angle_match_deg);
  result.hysteresis = HysteresisOf(result.points, options.angle_match_deg);
  result.repeatability = RepeatabilityOf(result.points, options.angle_match_deg);
  if (!result.hysteresis.available) {
    result.warnings.push_back(fmt::format(
        "hysteresis was not measured (no angle visited both turning up and turning down): the "
        "corrected U assumes up to {} deg (--assumed-hysteresis-deg); sweep up and back down "
        "to measure it",
        options.assumed_hysteresis_deg));
  }

  // Stage: cross-axis.
  for (int j = 0; j < 2; ++j) result.cross_axis[j].quantity = kAxes[others[j]];
  if (angle[others[0]] == nullptr || angle[others[1]] == nullptr) {
    result.cross_axis_available = false;
    result.cross_axis_note = fmt::format(
        "the session has the tag's {} only: cross-axis coupling ({} and {}) is not evaluated",
        kAxes[turned], kAxes[others[0]], kAxes[others[1]]);
    result.warnings.push_back(result.cross_axis_note);
  } else {
    for (int j = 0; j < 2; ++j) {
      const std::vector<double>& v = angle[others[j]]->values;
      const PlateauNoise noise = PlateauNoiseOf(v, result.segmentation.plateaus);
      std::vector<double> means, us;
      for (AccuracyPoint& pt : result.points) {
        const Plateau& p = result.segmentation.plateaus[pt.index];
        pt.other_mean_deg[j] = AngleMean(v, p.begin, p.end);
        pt.other_u_deg[j] =
            std::max(noise.sigma_deg * std::sqrt(Ar1MeanVarianceFactor(p.n(), noise.phi)),
                     options.resolution_deg / std::sqrt(12.0 * static_cast<double>(p.n())));
        means.push_back(pt.other_mean_deg[j]);
        us.push_back(pt.other_u_deg[j]);
      }
      result.cross_axis[j] =
          CrossAxisOf(kAxes[others[j]], result.points, means, us, options.angle_match_deg);
    }
  }

  // Stage: budgets.
  if (Status s = ReadingBudgets(options, &result); !s.ok()) return s.error();
  if (options.reference.u_deg == 0.0) {
    result.warnings.push_back(
        "no reference uncertainty given: the table is treated as exact (--reference-u DEG)");
  }
  if (result.fit.covariance_scaled) {
    result.warnings.push_back(fmt::format(
        "the plateau errors scatter about the curve {:.3g} times more (in variance) than their "
        "Type A u allow; the fit covariance is scaled by the reduced chi-square",
        result.fit.reduced_chi2));
  }
  return result;
}

}  // namespace metro
