#include "metro/accuracy/accuracy.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "metro/core/angles.hpp"
#include "metro/stats/derived_quantity.hpp"
#include "metro/uncertainty/budget.hpp"

namespace metro {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Mean of an angle series that may cross +-180 deg: unwrapped, averaged, wrapped back.
Result<TypeAResult> AngleTypeA(const std::vector<double>& values, size_t begin, size_t end,
                               const TypeAOptions& options) {
  std::vector<double> v(values.begin() + static_cast<std::ptrdiff_t>(begin),
                        values.begin() + static_cast<std::ptrdiff_t>(end));
  UnwrapDegInPlace(&v);
  auto r = EvaluateTypeA(v.data(), v.size(), options);
  if (r.ok()) r.value().mean = WrapDeg180(r.value().mean);
  return r;
}

// Clusters of reference angles closer than match_deg (sorted by angle): cluster id per point.
std::vector<size_t> ClusterAngles(const std::vector<AccuracyPoint>& points, double match_deg,
                                  std::vector<double>* centres) {
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return points[a].reference_deg < points[b].reference_deg; });
  std::vector<size_t> id(points.size(), 0);
  centres->clear();
  std::vector<size_t> counts;
  for (size_t k = 0; k < order.size(); ++k) {
    const size_t i = order[k];
    if (k == 0 || points[i].reference_deg - points[order[k - 1]].reference_deg > match_deg) {
      centres->push_back(0.0);
      counts.push_back(0);
    }
    id[i] = centres->size() - 1;
    centres->back() += points[i].reference_deg;
    ++counts.back();
  }
  for (size_t c = 0; c < centres->size(); ++c) (*centres)[c] /= static_cast<double>(counts[c]);
  return id;
}

// Mean error of a group of plateaus and its standard uncertainty: the larger of the
// between-plateau s/sqrt(m) (dof m - 1) and the within-plateau sqrt(sum u_i^2)/m (dof: the
// smallest plateau dof).
struct GroupMean {
  double mean = 0.0, u = 0.0, dof = 0.0;
  int count = 0;
};
GroupMean MeanOfGroup(const std::vector<const AccuracyPoint*>& group) {
  GroupMean g;
  g.count = static_cast<int>(group.size());
  if (group.empty()) return g;
  const double m = static_cast<double>(group.size());
  double sum = 0.0, sum_u2 = 0.0, min_dof = kInf;
  for (const AccuracyPoint* p : group) {
    sum += p->error_deg;
    sum_u2 += p->type_a.u_deg * p->type_a.u_deg;
    min_dof = std::min(min_dof, p->type_a.dof);
  }
  g.mean = sum / m;
  const double within = sum_u2 / (m * m);
  g.u = std::sqrt(within);
  g.dof = min_dof;
  if (group.size() >= 2) {
    double ss = 0.0;
    for (const AccuracyPoint* p : group) ss += (p->error_deg - g.mean) * (p->error_deg - g.mean);
    const double between = ss / (m - 1.0) / m;
    if (between > within) {
      g.u = std::sqrt(between);
      g.dof = m - 1.0;
    }
  }
  return g;
}

BudgetInput NormalInput(const std::string& name, double u, double dof, const std::string& note) {
  BudgetInput in;
  in.name = name;
  in.distribution = Distribution::kNormal;
  in.u = u;
  in.dof = dof > 0.0 ? dof : kInf;
  in.sensitivity = 1.0;
  in.unit = "deg";
  in.note = note;
  return in;
}

Result<ReadingBudget> EvaluateReadingBudget(const std::string& name,
                                            const std::vector<BudgetInput>& inputs,
                                            double coverage) {
  Budget budget;
  budget.file = name + " reading budget";
  budget.measurand = "error of a single " + name + " tag reading";
  budget.unit = "deg";
  budget.inputs = inputs;
  budget.gum.coverage = coverage;
  budget.monte_carlo.enabled = false;
  if (Status s = ValidateBudget(budget); !s.ok()) return s.error();
  auto gum = EvaluateGum(budget);
  if (!gum.ok()) return gum.error();
  ReadingBudget rb;
  rb.name = name;
  rb.gum = gum.value();
  for (const BudgetInput& in : inputs) rb.notes.push_back(in.note);
  return rb;
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
  const char* const kAxes[3] = {"yaw_deg", "pitch_deg", "roll_deg"};
  const Quantity* angle[3];
  for (int a = 0; a < 3; ++a) {
    angle[a] = tag->Find(kAxes[a]);
    if (angle[a] == nullptr) {
      const std::optional<std::string> gap = MissingDerivationInputs(*tag, kAxes[a]);
      return MakeError(session.path, 0,
                       fmt::format("tag {} has no {} ({}): the accuracy evaluation needs the "
                                   "tag's yaw_deg, pitch_deg and roll_deg",
                                   tag->sensor, kAxes[a],
                                   gap ? *gap : "nor a quaternion qw..qz to derive it from"));
    }
  }
  const int turned = static_cast<int>(options.axis);
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
    auto aligned = AlignReference(tag->t_s, tag_angle, ref_tag->t_s,
                                  ref_tag->Find("table_angle_deg")->values, options.alignment);
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
  std::vector<double> error(tag_angle.size());
  for (size_t k = 0; k < error.size(); ++k) {
    error[k] = std::isnan(ref[k]) ? ref[k] : WrapDeg180(tag_angle[k] - ref[k]);
  }

  // Plateaus and per-plateau Type A (JCGM 100 4.2; Zhang n_eff).
  auto seg = FindPlateaus(tag->t_s, ref, error, options.plateaus);
  if (!seg.ok()) {
    Error e = seg.error();
    e.file = result.separate_reference ? reference->path : session.path;
    return e;
  }
  result.segmentation = std::move(seg).value();
  double pooled_ss = 0.0, pooled_df = 0.0, pooled_dof = 0.0;
  int sweep = 1;
  int settle_at_limit = 0;
  for (size_t i = 0; i < result.segmentation.plateaus.size(); ++i) {
    const Plateau& p = result.segmentation.plateaus[i];
    auto ta = AngleTypeA(error, p.begin, p.end, options.type_a);
    if (!ta.ok()) return ta.error();
    const TypeAResult& t = ta.value();
    AccuracyPoint pt;
    pt.index = i;
    pt.reference_deg = p.reference_deg;
    pt.error_deg = t.mean;
    pt.mean_deg = WrapDeg180(p.reference_deg + t.mean);
    pt.type_a.n = t.n;
    pt.type_a.std_deg = t.std;
    // u of the plateau mean: the larger of Zhang's (type_a.hpp) and the AR(1) form
    // n_eff = n (1 - rho1) / (1 + rho1) (Zwiers & von Storch, J. Climate 8 (1995) 336), since
    // Zhang's lag cut-off truncates the slowly decaying correlation of a short DMP plateau;
    // floored by the packets' quantisation, q / sqrt(12 n) (JCGM 100 F.2.2.1).
    const double n = static_cast<double>(t.n);
    const double rho1 = std::clamp(t.rho1, 0.0, 0.99);
    const double n_eff_ar1 = n * (1.0 - rho1) / (1.0 + rho1);
    pt.type_a.n_eff = std::min(t.n_eff, n_eff_ar1);
    const double floor_u = options.resolution_deg / std::sqrt(12.0 * n);
    pt.type_a.u_deg = std::max(t.std / std::sqrt(pt.type_a.n_eff), floor_u);
    pt.type_a.dof = std::max(pt.type_a.n_eff - 1.0, 1.0);
    pt.t_start_s = p.t_start_s;
    pt.t_end_s = p.t_end_s;
    pt.settle_samples = p.settle_samples;
    if (i > 0) {
      const double move = p.reference_deg - result.points.back().reference_deg;
      pt.direction = move > 0.0 ? 1 : -1;
      if (pt.direction > 0 && result.points.back().direction < 0) ++sweep;
    }
    pt.sweep = sweep;
    for (int j = 0; j < 2; ++j) {
      auto other = AngleTypeA(angle[others[j]]->values, p.begin, p.end, options.type_a);
      if (!other.ok()) return other.error();
      pt.other_mean_deg[j] = other.value().mean;
    }
    pooled_ss += (static_cast<double>(t.n) - 1.0) * t.variance;
    pooled_df += static_cast<double>(t.n) - 1.0;
    pooled_dof += pt.type_a.dof;
    if (p.settle_at_limit) ++settle_at_limit;
    result.points.push_back(pt);
  }
  if (settle_at_limit > 0) {
    result.warnings.push_back(fmt::format(
        "{} of {} plateaus: MSER-5 settling reached half the plateau; the tag may not have "
        "settled there (dwell longer, or set --settle-s)",
        settle_at_limit, result.points.size()));
  }
  result.reading_std_deg = std::sqrt(pooled_ss / pooled_df);
  result.reading_dof = pooled_dof;

  // Systematic error over the sweep.
  {
    const double m = static_cast<double>(result.points.size());
    double sum = 0.0, sum2 = 0.0;
    SystematicError& s = result.systematic;
    for (const AccuracyPoint& p : result.points) {
      sum += p.error_deg;
      sum2 += p.error_deg * p.error_deg;
      if (std::fabs(p.error_deg) > s.max_abs_deg) {
        s.max_abs_deg = std::fabs(p.error_deg);
        s.at_reference_deg = p.reference_deg;
      }
    }
    s.mean_deg = sum / m;
    s.rms_deg = std::sqrt(sum2 / m);
    double ss = 0.0;
    for (const AccuracyPoint& p : result.points) {
      ss += (p.error_deg - s.mean_deg) * (p.error_deg - s.mean_deg);
    }
    s.std_deg = result.points.size() > 1 ? std::sqrt(ss / (m - 1.0)) : 0.0;
  }

  // The error curve (weighted least squares, error_fit.hpp).
  std::vector<FitPoint> fit_points;
  for (const AccuracyPoint& p : result.points) {
    fit_points.push_back({p.reference_deg, p.error_deg, p.type_a.u_deg});
  }
  auto model = ChooseErrorModel(fit_points, options.model, options.angle_match_deg);
  if (!model.ok()) {
    Error e = model.error();
    e.file = session.path;
    return e;
  }
  result.model = model.value();
  auto fit = FitHarmonicModel(fit_points, ErrorModelTerms(result.model));
  if (!fit.ok()) return fit.error();
  result.fit = std::move(fit).value();
  for (const AccuracyPoint& p : result.points) {
    result.max_prediction_u_deg =
        std::max(result.max_prediction_u_deg, result.fit.PredictionU(p.reference_deg));
  }

  // Angle groups for linearity, hysteresis and repeatability.
  std::vector<double> centres;
  const std::vector<size_t> cluster =
      ClusterAngles(result.points, options.angle_match_deg, &centres);
  const size_t angles = centres.size();
  {
    // Linearity: the per-angle mean errors about their least-squares straight line.
    std::vector<double> mean(angles, 0.0), count(angles, 0.0);
    for (size_t i = 0; i < result.points.size(); ++i) {
      mean[cluster[i]] += result.points[i].error_deg;
      count[cluster[i]] += 1.0;
    }
    for (size_t c = 0; c < angles; ++c) mean[c] /= count[c];
    Linearity& lin = result.linearity;
    lin.angles = angles;
    double tx = 0.0, ty = 0.0;
    for (size_t c = 0; c < angles; ++c) {
      tx += centres[c];
      ty += mean[c];
    }
    tx /= static_cast<double>(angles);
    ty /= static_cast<double>(angles);
    double sxx = 0.0, sxy = 0.0;
    for (size_t c = 0; c < angles; ++c) {
      sxx += (centres[c] - tx) * (centres[c] - tx);
      sxy += (centres[c] - tx) * (mean[c] - ty);
    }
    lin.line_slope = sxx > 0.0 ? sxy / sxx : 0.0;
    lin.line_offset_deg = ty - lin.line_slope * tx;
    double ss = 0.0;
    for (size_t c = 0; c < angles; ++c) {
      const double d = mean[c] - (lin.line_offset_deg + lin.line_slope * centres[c]);
      ss += d * d;
      if (std::fabs(d) >= lin.max_abs_deviation_deg) {
        lin.max_abs_deviation_deg = std::fabs(d);
        lin.at_reference_deg = centres[c];
      }
    }
    lin.rms_deviation_deg = std::sqrt(ss / static_cast<double>(angles));
    const double span = centres.back() - centres.front();
    lin.percent_of_span = span > 0.0 ? 100.0 * lin.max_abs_deviation_deg / span : 0.0;
  }
  {
    // Hysteresis: up minus down at each angle visited both ways.
    Hysteresis& h = result.hysteresis;
    double sw = 0.0, swh = 0.0, chi2 = 0.0;
    for (size_t c = 0; c < angles; ++c) {
      std::vector<const AccuracyPoint*> up, down;
      for (size_t i = 0; i < result.points.size(); ++i) {
        if (cluster[i] != c) continue;
        if (result.points[i].direction > 0) up.push_back(&result.points[i]);
        if (result.points[i].direction < 0) down.push_back(&result.points[i]);
      }
      if (up.empty() || down.empty()) continue;
      const GroupMean gu = MeanOfGroup(up), gd = MeanOfGroup(down);
      HysteresisPair pair;
      pair.reference_deg = centres[c];
      pair.up_error_deg = gu.mean;
      pair.down_error_deg = gd.mean;
      pair.hysteresis_deg = gu.mean - gd.mean;
      pair.u_deg = std::hypot(gu.u, gd.u);
      // JCGM 100 G.4.1 for the difference of two independent means.
      pair.dof =
          std::pow(pair.u_deg, 4) / (std::pow(gu.u, 4) / gu.dof + std::pow(gd.u, 4) / gd.dof);
      pair.up_count = gu.count;
      pair.down_count = gd.count;
      h.pairs.push_back(pair);
    }
    if (h.pairs.empty()) {
      h.note =
          "no table angle was visited both turning up and turning down: sweep up and back down "
          "through the same angles to measure hysteresis";
    } else {
      h.available = true;
      for (const HysteresisPair& p : h.pairs) {
        const double w = 1.0 / (p.u_deg * p.u_deg);
        sw += w;
        swh += w * p.hysteresis_deg;
        if (std::fabs(p.hysteresis_deg) >= h.max_abs_deg) {
          h.max_abs_deg = std::fabs(p.hysteresis_deg);
          h.u_max_abs_deg = p.u_deg;
          h.at_reference_deg = p.reference_deg;
        }
      }
      h.mean_deg = swh / sw;
      for (const HysteresisPair& p : h.pairs) {
        chi2 += std::pow((p.hysteresis_deg - h.mean_deg) / p.u_deg, 2);
      }
      // Inverse-variance weighted mean; u enlarged by the Birge ratio sqrt(chi2/(k-1)) when
      // the pairs scatter more than their u's allow (hysteresis that varies with angle).
      const double k = static_cast<double>(h.pairs.size());
      const double birge = h.pairs.size() > 1 ? std::sqrt(chi2 / (k - 1.0)) : 1.0;
      h.u_mean_deg = std::sqrt(1.0 / sw) * std::max(1.0, birge);
      h.note = fmt::format("{} angle(s) visited both ways; mean weighted by 1/u^2, its u {}",
                           h.pairs.size(),
                           birge > 1.0 ? "enlarged by the Birge ratio" : "from the pairs' u");
    }
  }
  {
    // Repeatability (ISO 5725-2): pooled s of plateau errors at the same angle and direction.
    Repeatability& r = result.repeatability;
    r.sweeps = result.points.empty() ? 0 : result.points.back().sweep;
    double ss = 0.0, df = 0.0;
    for (size_t c = 0; c < angles; ++c) {
      for (int d : {-1, 0, 1}) {
        std::vector<double> e;
        for (size_t i = 0; i < result.points.size(); ++i) {
          if (cluster[i] == c && result.points[i].direction == d) {
            e.push_back(result.points[i].error_deg);
          }
        }
        if (e.size() < 2) continue;
        const double mean =
            std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(e.size());
        for (double v : e) ss += (v - mean) * (v - mean);
        df += static_cast<double>(e.size()) - 1.0;
        ++r.groups;
      }
    }
    if (df > 0.0) {
      r.available = true;
      r.s_r_deg = std::sqrt(ss / df);
      r.dof = df;
      r.note =
          fmt::format("pooled over {} (angle, direction) group(s) with >= 2 plateaus", r.groups);
    } else {
      r.note =
          "no table angle was visited twice in the same direction: repeat the sweep at least "
          "twice to measure repeatability";
    }
  }
  // Cross-axis coupling: the two axes not turned.
  for (int j = 0; j < 2; ++j) {
    CrossAxis& x = result.cross_axis[j];
    x.quantity = kAxes[others[j]];
    std::vector<double> v;
    for (const AccuracyPoint& p : result.points) v.push_back(p.other_mean_deg[j]);
    UnwrapDegInPlace(&v);
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    x.span_deg = *hi - *lo;
    x.mean_deg =
        WrapDeg180(std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size()));
    std::vector<FitPoint> pts;
    for (size_t i = 0; i < v.size(); ++i) {
      pts.push_back({result.points[i].reference_deg, v[i], result.points[i].type_a.u_deg});
    }
    const AngleCoverage cov = CoverageOf(pts, options.angle_match_deg);
    if (cov.distinct >= 5 && cov.span_deg >= 180.0) {
      auto f = FitHarmonicModel(pts, {ErrorTerm::kOffset, ErrorTerm::kCos1, ErrorTerm::kSin1});
      if (f.ok()) {
        x.fitted = true;
        x.fit = std::move(f).value();
        const double a = x.fit.params[1], b = x.fit.params[2];
        x.amplitude_deg = std::hypot(a, b);
        if (x.amplitude_deg > 0.0) {
          // JCGM 100 5.2.2: g = (a, b) / A on the (a1, b1) block of the covariance.
          const double ga = a / x.amplitude_deg, gb = b / x.amplitude_deg;
          const auto& c = x.fit.covariance;
          x.u_amplitude_deg = std::sqrt(
              std::max(0.0, ga * ga * c[1][1] + 2.0 * ga * gb * c[1][2] + gb * gb * c[2][2]));
        }
      }
    }
  }

  // Budgets of a single reading (JCGM 100 5.1.2, G.4.1, 6.2 via EvaluateGum).
  const std::string ref_note =
      options.reference.u_deg > 0.0
          ? "table certificate (" + options.reference.source + "), standard uncertainty"
          : "table certificate not given: the table is treated as exact (give --reference-u)";
  const BudgetInput reading = NormalInput(
      "reading_noise", result.reading_std_deg, result.reading_dof,
      "Type A: pooled standard deviation of one reading over the plateaus (dof: sum of n_eff - 1)");
  const BudgetInput table =
      NormalInput("reference", options.reference.u_deg, options.reference.dof, ref_note);
  BudgetInput resolution;
  resolution.name = "resolution";
  resolution.distribution = Distribution::kRectangular;
  resolution.half_width = options.resolution_deg / 2.0;
  resolution.u = options.resolution_deg / std::sqrt(12.0);  // JCGM 100 F.2.2.1
  resolution.sensitivity = 1.0;
  resolution.unit = "deg";
  resolution.note = fmt::format("{} deg packet resolution, rectangular, q/sqrt(12) (F.2.2.1)",
                                options.resolution_deg);
  const double fit_dof = result.fit.dof > 0 ? result.fit.dof : kInf;
  const BudgetInput prediction =
      NormalInput("fit_prediction", result.max_prediction_u_deg, fit_dof,
                  "u of the fitted correction, max over the plateaus of sqrt(g^T C g) (dof m - p)");
  const BudgetInput residual = NormalInput(
      "fit_residual", result.fit.residual_rms_deg, fit_dof,
      "scatter of the plateau errors about the curve (hysteresis, repeatability, lack of fit): "
      "sqrt(sum r_i^2 / (m - p))");
  const BudgetInput systematic = NormalInput(
      "systematic_error", result.systematic.rms_deg, static_cast<double>(result.points.size()),
      "uncorrected error over the range: RMS of the plateau errors about zero, "
      "sqrt(mean^2 + variance over the range) (JCGM 100 F.2.4.5; dof m)");
  auto corrected = EvaluateReadingBudget(
      "corrected", {reading, prediction, residual, table, resolution}, options.coverage);
  if (!corrected.ok()) return corrected.error();
  result.corrected = std::move(corrected).value();
  auto uncorrected = EvaluateReadingBudget("uncorrected", {systematic, reading, table, resolution},
                                           options.coverage);
  if (!uncorrected.ok()) return uncorrected.error();
  result.uncorrected = std::move(uncorrected).value();
  auto random = EvaluateReadingBudget("random", {reading, table, resolution}, options.coverage);
  if (!random.ok()) return random.error();
  result.random_expanded_deg = random.value().gum.expanded;
  result.uncorrected_max_abs_expanded_deg =
      result.random_expanded_deg + result.systematic.max_abs_deg;
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
