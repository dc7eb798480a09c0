// EvaluateSessionTypeA runs these stages, in this order (method: docs/type-a.md):
//
//   selection   CheckSelection, Select        --sensor, --quantity; tags, quantities,
//                                             explicit windows; CheckWindowNotEmpty
//   settle      DetectTransients, CutSettled, with --settle auto: each quantity's transient
//               WarnOnTransient               (on all cores), the tag's cut, warnings
//   times       FillWindowTimes               the window's first and last t_s and lines
//   evaluation  EvaluateQuantity, WarnOnTypeA, Type A of every (tag, quantity) on all cores,
//               WarnOnGimbalLock              with its warnings
#include "metro/stats/session_type_a.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hpp"
#include "metro/core/angles.hpp"
#include "metro/io/columns.hpp"
#include "metro/stats/derived_quantity.hpp"
#include "metro/stats/quantization.hpp"

namespace metro {
namespace {

std::string JoinSensors(const Session& session) {
  std::vector<int> sensors;
  for (const Tag& t : session.tags) sensors.push_back(t.sensor);
  return fmt::format("{}", fmt::join(sensors, ", "));
}

bool Selected(const std::vector<std::string>& wanted, const std::string& name) {
  return wanted.empty() || std::find(wanted.begin(), wanted.end(), name) != wanted.end();
}

// The quantity's values in [begin, end), unwrapped if it is a wrapping angle.
std::vector<double> WindowValues(const Quantity& q, size_t begin, size_t end, int* jumps) {
  std::vector<double> x(q.values.begin() + static_cast<ptrdiff_t>(begin),
                        q.values.begin() + static_cast<ptrdiff_t>(end));
  *jumps = IsWrappingAngle(q.name) ? UnwrapDegInPlace(&x) : 0;
  return x;
}

// A temperature never decides a tag-wide settle cut.
bool IsTemperature(const Quantity& q) {
  const Unit* unit = UnitBySymbol(q.unit);
  return unit != nullptr && unit->dimension == Dimension::kTemperature;
}

// True when x[0, n) holds at most two distinct values; noisy data leave at the third value.
bool AtMostTwoValues(const double* x, size_t n) {
  if (n == 0) return true;
  const double first = x[0];
  double second = first;
  for (size_t i = 1; i < n; ++i) {
    if (x[i] == first || x[i] == second) continue;
    if (second != first) return false;
    second = x[i];
  }
  return true;
}

// Table columns may be empty ("unknown"): those observations are left out.
std::vector<double> Finite(std::vector<double> x, size_t* dropped) {
  const auto it = std::remove_if(x.begin(), x.end(), [](double v) { return !std::isfinite(v); });
  *dropped = static_cast<size_t>(x.end() - it);
  x.erase(it, x.end());
  return x;
}

}  // namespace

AppliedWindow ExplicitWindow(const Tag& tag, const WindowOptions& w) {
  AppliedWindow a;
  a.n_total = tag.size();
  size_t begin = std::min<size_t>(tag.size(), static_cast<size_t>(w.skip_samples));
  if (w.skip_seconds > 0.0 && !tag.t_s.empty()) {
    const double t0 = tag.t_s.front() + w.skip_seconds;
    begin =
        std::max(begin, static_cast<size_t>(std::lower_bound(tag.t_s.begin(), tag.t_s.end(), t0) -
                                            tag.t_s.begin()));
  }
  size_t end = tag.size();
  if (w.from_s) {
    begin = std::max(
        begin, static_cast<size_t>(std::lower_bound(tag.t_s.begin(), tag.t_s.end(), *w.from_s) -
                                   tag.t_s.begin()));
  }
  if (w.to_s) {
    end = std::min(end,
                   static_cast<size_t>(std::upper_bound(tag.t_s.begin(), tag.t_s.end(), *w.to_s) -
                                       tag.t_s.begin()));
  }
  a.begin = std::min(begin, end);
  a.end = end;
  return a;
}

namespace {

void FillWindowTimes(const Tag& tag, AppliedWindow* a) {
  if (a->n() == 0) return;
  a->t_first_s = tag.t_s[a->begin];
  a->t_last_s = tag.t_s[a->end - 1];
  a->first_line = tag.line[a->begin];
  a->last_line = tag.line[a->end - 1];
}

struct Job {
  size_t tag;
  size_t quantity;  // Index into the tag's quantities.
  size_t slot;      // Index into TagTypeA::quantities.
};

}  // namespace

bool IsWrappingAngle(const std::string& name) {
  return name == "yaw_deg" || name == "roll_deg" || name == "table_angle_deg";
}

bool WindowOptions::IsValid(std::string* why) const {
  auto fail = [&](const char* m) {
    if (why) *why = m;
    return false;
  };
  if (skip_samples < 0) return fail("skip_samples must be >= 0");
  if (!(skip_seconds >= 0.0) || !std::isfinite(skip_seconds)) {
    return fail("skip_seconds must be a finite number >= 0");
  }
  if (from_s && !std::isfinite(*from_s)) return fail("from_s must be finite");
  if (to_s && !std::isfinite(*to_s)) return fail("to_s must be finite");
  if (from_s && to_s && !(*from_s < *to_s)) return fail("from_s must be before to_s");
  if (settle_tag_wide && !settle_auto) {
    return fail("a tag-wide settle cut (--settle-scope tag) needs --settle auto");
  }
  if (!settle.IsValid(why)) return false;
  return true;
}

bool SessionTypeAOptions::IsValid(std::string* why) const {
  if (!window.IsValid(why)) return false;
  if (!type_a.IsValid(why)) return false;
  if (threads < 0) {
    if (why) *why = "threads must be >= 0";
    return false;
  }
  return true;
}

namespace {

// An explicit window (skip, from, to) that leaves no observation of any tag is an input
// error naming the span the tags have; one that empties some tags but not others is a
// warning on those tags.
Status CheckWindowNotEmpty(const Session& session, const WindowOptions& window,
                           const std::vector<const Tag*>& tags, SessionTypeA* out) {
  const bool explicit_window = window.skip_samples > 0 || window.skip_seconds > 0.0 ||
                               window.from_s.has_value() || window.to_s.has_value();
  if (!explicit_window) return {};
  bool any_left = false, any_data = false;
  double t_min = std::numeric_limits<double>::infinity(), t_max = -t_min;
  for (size_t k = 0; k < tags.size(); ++k) {
    const Tag& tag = *tags[k];
    if (tag.size() == 0) continue;
    any_data = true;
    t_min = std::min(t_min, tag.t_s.front());
    t_max = std::max(t_max, tag.t_s.back());
    if (out->tags[k].window.n() > 0) {
      any_left = true;
    } else {
      out->tags[k].warnings.push_back(fmt::format(
          "the window leaves no observations of this tag (its observations span t_s {:.6g} .. "
          "{:.6g}, {} of them)",
          tag.t_s.front(), tag.t_s.back(), tag.size()));
    }
  }
  if (!any_data || any_left) return {};
  std::string given;
  if (window.skip_samples > 0) given += fmt::format(" --skip-samples {}", window.skip_samples);
  if (window.skip_seconds > 0.0) given += fmt::format(" --skip-seconds {:g}", window.skip_seconds);
  if (window.from_s) given += fmt::format(" --from-s {:g}", *window.from_s);
  if (window.to_s) given += fmt::format(" --to-s {:g}", *window.to_s);
  Error e = MakeError(fmt::format(
      "the window ({}) leaves no observations of any tag: the session's observations span t_s "
      "{:.6g} .. {:.6g}; choose a window inside that span",
      given.empty() ? std::string() : given.substr(1), t_min, t_max));
  e.file = session.path;
  return e;
}

// ---- selection ----------------------------------------------------------------------------

// Every --sensor and --quantity asked for is in the session.
Status CheckSelection(const Session& session, const SessionTypeAOptions& options) {
  for (int sensor : options.sensors) {
    if (session.FindTag(sensor) == nullptr) {
      return MakeError(session.path, 0,
                       fmt::format("--sensor {}: no such tag in the session (tags: {})", sensor,
                                   JoinSensors(session)));
    }
  }
  for (const std::string& name : options.quantities) {
    bool found = false;
    for (const Tag& t : session.tags) found = found || t.Find(name) != nullptr;
    if (!found) {
      if (std::optional<std::string> why_absent = MissingDerivationInputs(session, name)) {
        return MakeError(
            session.path, 0,
            fmt::format("--quantity {}: no such quantity in the session: {}", name, *why_absent));
      }
      std::vector<std::string> names;
      for (const Tag& t : session.tags) {
        for (const Quantity& q : t.quantities) {
          if (std::find(names.begin(), names.end(), q.name) == names.end()) names.push_back(q.name);
        }
      }
      return MakeError(session.path, 0,
                       fmt::format("--quantity {}: no such quantity in the session (quantities: "
                                   "{})",
                                   name, fmt::join(names, ", ")));
    }
  }
  return Status::Ok();
}

// The selected tags, in session order, beside out->tags.
struct Selection {
  std::vector<const Tag*> tags;
  // source[k][slot]: the index in tags[k]->quantities of out.tags[k].quantities[slot] (no
  // name lookups: a file of 10^4 columns would make them quadratic).
  std::vector<std::vector<size_t>> source;
};

// The selected tags and quantities, with their explicit windows, as out->tags.
Selection Select(const Session& session, const SessionTypeAOptions& options, SessionTypeA* out) {
  Selection selection;
  for (const Tag& tag : session.tags) {
    if (!options.sensors.empty() && std::find(options.sensors.begin(), options.sensors.end(),
                                              tag.sensor) == options.sensors.end()) {
      continue;
    }
    selection.tags.push_back(&tag);
    TagTypeA t;
    t.sensor = tag.sensor;
    t.counts = tag.counts;
    t.window = ExplicitWindow(tag, options.window);
    if (tag.size() == 0) {
      t.warnings.push_back(fmt::format("no fresh observations (frames {}, stale {}, never {})",
                                       tag.counts.frames, tag.counts.stale, tag.counts.never));
    }
    selection.source.emplace_back();
    for (size_t i = 0; i < tag.quantities.size(); ++i) {
      const Quantity& q = tag.quantities[i];
      if (!Selected(options.quantities, q.name)) continue;
      selection.source.back().push_back(i);
      QuantityTypeA r;
      r.name = q.name;
      r.unit = q.unit;
      r.origin = q.origin;
      r.angle_handling = IsWrappingAngle(q.name) ? "unwrapped" : "linear";
      t.quantities.push_back(std::move(r));
    }
    out->tags.push_back(std::move(t));
  }
  return selection;
}

// One job per (tag, selected quantity).
std::vector<Job> JobsOf(const Selection& selection, const SessionTypeA& out) {
  std::vector<Job> jobs;
  for (size_t k = 0; k < selection.tags.size(); ++k) {
    for (size_t slot = 0; slot < out.tags[k].quantities.size(); ++slot) {
      jobs.push_back({k, selection.source[k][slot], slot});
    }
  }
  return jobs;
}

// ---- settle -------------------------------------------------------------------------------

// Settle detection (stats/settle.hpp): each quantity's own cut (QuantityTypeA::settle). The
// fits run on all cores (each is O(n) per trial tau).
void DetectTransients(const Selection& selection, const SessionTypeAOptions& options,
                      SessionTypeA* out) {
  const std::vector<Job> settle_jobs = JobsOf(selection, *out);
  internal::ParallelFor(settle_jobs.size(), options.threads, [&](size_t j) {
    const Job& job = settle_jobs[j];
    const TagTypeA& t = out->tags[job.tag];
    QuantityTypeA& r = out->tags[job.tag].quantities[job.slot];
    int jumps = 0;
    size_t dropped = 0;
    const std::vector<double> x =
        Finite(WindowValues(selection.tags[job.tag]->quantities[job.quantity], t.window.begin,
                            t.window.end, &jumps),
               &dropped);
    if (dropped > 0) {
      // Columns with gaps (table_*): no time axis to fit a transient on.
      r.settle.note = "empty (unknown) values in the window: not examined for a transient";
      return;
    }
    r.settle = DetectSettleTransient(x.data(), x.size(), options.window.settle);
    r.settle_samples = r.settle.samples;
  });
}

// The warning, if any, on a quantity whose transient cut a large part of a window of
// n_window samples (period_s apart).
void WarnOnTransient(size_t n_window, double period_s, QuantityTypeA* r) {
  const SettleResult& s = r->settle;
  if (!s.fitted || s.samples == 0) return;
  const std::string what = fmt::format(
      "--settle auto: {}: start-up transient of tau = {:.3g} samples ({:.3g} s), "
      "amplitude {:.3g} {} ({:.1f} u(A))",
      r->name, s.tau_samples, s.tau_samples * period_s, s.amplitude, r->unit, s.t_ratio);
  if (s.at_limit) {
    r->warnings.push_back(fmt::format(
        "{}: it did not decay within the first half of the window ({} of {} samples "
        "dropped); what remains biases the mean by about {:.2g} u: the quantity may still "
        "be settling or drifting",
        what, s.samples, n_window, s.bias_over_u_kept));
  } else if (static_cast<double>(s.samples) > 0.1 * static_cast<double>(n_window)) {
    r->warnings.push_back(fmt::format(
        "{}: {} of {} samples ({:.0f} %) dropped, until the remaining transient biases the "
        "mean by at most {:.2g} u (it biased the whole window's mean by {:.2g} u)",
        what, s.samples, n_window,
        100.0 * static_cast<double>(s.samples) / static_cast<double>(n_window), s.bias_over_u_kept,
        s.bias_over_u_uncut));
  }
}

// The tag window takes the largest cut of a non-temperature quantity, and with
// settle_tag_wide so does every quantity; the warnings that go with the cuts.
void CutSettled(const Tag& tag, const std::vector<size_t>& source, const WindowOptions& window,
                TagTypeA* t) {
  size_t settle = 0;
  const QuantityTypeA* driver = nullptr;
  for (size_t slot = 0; slot < t->quantities.size(); ++slot) {
    QuantityTypeA& r = t->quantities[slot];
    const Quantity* q = &tag.quantities[source[slot]];
    if (!IsTemperature(*q) && r.settle.samples > settle) {
      settle = r.settle.samples;
      driver = &r;
    }
  }
  const size_t explicit_begin = t->window.begin;
  const size_t n_window = t->window.n();
  t->window.settle_samples = settle;
  t->window.settle_at_limit = driver != nullptr && driver->settle.at_limit;
  t->window.settle_driver = driver != nullptr ? driver->name : "";
  t->window.begin = std::min(t->window.end, explicit_begin + settle);
  const double period_s = n_window > 1 ? (tag.t_s[t->window.end - 1] - tag.t_s[explicit_begin]) /
                                             static_cast<double>(n_window - 1)
                                       : 0.0;
  for (QuantityTypeA& r : t->quantities) {
    r.window_begin = window.settle_tag_wide
                         ? t->window.begin
                         : std::min(t->window.end, explicit_begin + r.settle_samples);
    WarnOnTransient(n_window, period_s, &r);
  }
  if (driver != nullptr && window.settle_tag_wide) {
    t->warnings.push_back(fmt::format(
        "--settle-scope tag: every quantity of the tag cut at {} samples, the cut of {} "
        "(temperature never decides it)",
        settle, driver->name));
  }
  if (driver != nullptr && driver->settle.at_limit) {
    t->warnings.push_back(fmt::format(
        "--settle auto: {}'s transient did not end within the first half of the window ({} "
        "samples dropped); it may still be settling or drifting",
        driver->name, settle));
  }
}

// ---- evaluation ---------------------------------------------------------------------------

}  // namespace

// The warnings a Type A result calls for (autocorrelation, drift).
void WarnOnTypeA(QuantityTypeA* r) {
  const TypeAResult& ta = r->type_a;
  if (ta.autocorr_computed && ta.n_eff < 0.5 * static_cast<double>(ta.n)) {
    r->warnings.push_back(
        fmt::format("n_eff = {:.1f} < n/2 = {:.1f}: the observations are autocorrelated; "
                    "std_of_mean ({:.3g}) understates the uncertainty of the mean, use "
                    "u_mean ({:.3g}, {} dof)",
                    ta.n_eff, 0.5 * static_cast<double>(ta.n), ta.std_of_mean, ta.u_mean,
                    fmt::format("{:.1f}", ta.u_mean_dof)));
  }
  if (ta.cutoff_reached_limit) {
    r->warnings.push_back(
        "the autocorrelation did not decay within n/4 lags (drift or a trend): even "
        "std_of_mean_autocorr is optimistic; see u_mean and the Allan deviation");
  }
  // Without the autocorrelation (autocorrelation off, n <= 3, or a cut-off beyond what the
  // streaming mode keeps) its note says why.
  if (!ta.u_mean_available || (!ta.autocorr_computed && ta.u_mean_ar > 0.0)) {
    r->warnings.push_back(ta.autocorr_note);
  }
  if (!ta.u_mean_note.empty()) r->warnings.push_back(ta.u_mean_note);
  if (ta.drift_detected) {
    r->warnings.push_back(fmt::format(
        "drift or a random walk: the stationarity check (means of {} batches) gives u of the "
        "mean {:.3g}, more than 2x the autoregressive {:.3g} (std_of_mean_autocorr {}); "
        "u_mean takes the batch-means value ({} dof). The mean of a drifting record depends "
        "on the window; see the Allan deviation",
        kStationarityBatches, ta.u_mean_batch, ta.u_mean_ar,
        ta.autocorr_computed ? fmt::format("{:.3g}", ta.std_of_mean_autocorr)
                             : std::string("not computed"),
        kStationarityBatches - 1));
  }
}

namespace {}  // namespace

void WarnOnGimbalLockFromMax(const std::string& name, QuantityOrigin origin,
                             double pitch_max_abs_deg, QuantityTypeA* r) {
  if (name == "pitch_deg" && pitch_max_abs_deg >= kGimbalLockWarnPitchDeg) {
    r->warnings.push_back(
        fmt::format("|pitch| reaches {:.2f} deg: near gimbal lock yaw and roll are ill-defined",
                    pitch_max_abs_deg));
  }
  // Near pitch +-90 deg only yaw - roll (or yaw + roll) is defined by the attitude: each
  // of them alone swings by up to 180 deg on a tiny rotation, and its spread is not
  // noise of the tag.
  if ((name == "yaw_deg" || name == "roll_deg") && pitch_max_abs_deg >= kGimbalLockWarnPitchDeg) {
    r->warnings.push_back(fmt::format(
        "{}{}: |pitch_deg| reaches {:.2f} deg in the window (gimbal lock at 90): yaw and "
        "roll are then ill-defined, only their sum or difference is; this mean and "
        "spread are not the tag's",
        name, origin == QuantityOrigin::kDerived ? " (derived from the quaternion)" : "",
        pitch_max_abs_deg));
  }
}

namespace {

// The gimbal-lock warnings: on pitch itself (its values x_begin..x_end as evaluated) and on
// yaw and roll when the tag's pitch nears 90 deg in the window.
void WarnOnGimbalLock(const Tag& tag, const Quantity& q, const AppliedWindow& w,
                      const double* x_begin, const double* x_end, QuantityTypeA* r) {
  double worst = 0.0;
  if (q.name == "pitch_deg") {
    for (const double* v = x_begin; v != x_end; ++v) worst = std::max(worst, std::abs(*v));
  } else if (q.name == "yaw_deg" || q.name == "roll_deg") {
    if (const Quantity* pitch = tag.Find("pitch_deg")) {
      for (size_t i = r->window_begin; i < w.end; ++i) {
        if (std::isfinite(pitch->values[i])) worst = std::max(worst, std::abs(pitch->values[i]));
      }
    }
  }
  WarnOnGimbalLockFromMax(q.name, q.origin, worst, r);
}

// One quantity of one tag over [r->window_begin, w.end): Type A and its warnings.
void EvaluateQuantity(const Tag& tag, const Quantity& q, const AppliedWindow& w,
                      const SessionTypeAOptions& options, QuantityTypeA* r) {
  size_t dropped = 0;
  // The window is evaluated where it lies unless it must be unwrapped or has empty
  // values to leave out: a copy of 360 k samples per series is as slow as the mean.
  // Empty values (NaN) make EvaluateTypeA fail, so the window is scanned for them only
  // then (a scan of every series would cost another read of all the columns).
  const double* window = q.values.data() + r->window_begin;
  size_t n = w.end - r->window_begin;
  std::vector<double> copy;
  auto copy_window = [&] {
    copy = Finite(WindowValues(q, r->window_begin, w.end, &r->unwrap_jumps), &dropped);
    window = copy.data();
    n = copy.size();
  };
  if (IsWrappingAngle(q.name)) copy_window();
  auto a = EvaluateTypeA(window, n, options.type_a);
  if (!a.ok() && copy.empty() &&
      !std::all_of(window, window + n, [](double v) { return std::isfinite(v); })) {
    copy_window();
    a = EvaluateTypeA(window, n, options.type_a);
  }
  if (a.ok() && AtMostTwoValues(window, n)) {
    // A window whose spread may hide the noise (no spread, or perhaps one step): with the
    // quantization step of the tag's whole record, Willink's rules for digitized readings
    // (type_a.hpp). Any other window is evaluated as before, without this extra read.
    TypeAOptions digitized = options.type_a;
    digitized.quantization_step = QuantizationStep(q.values);
    if (digitized.quantization_step > 0.0) a = EvaluateTypeA(window, n, digitized);
  }
  if (!a.ok()) {
    r->error = a.error().message;
    return;
  }
  r->ok = true;
  r->type_a = a.value();
  if (r->angle_handling == "unwrapped") r->type_a.mean = WrapDeg180(r->type_a.mean);
  if (dropped > 0) {
    r->warnings.push_back(fmt::format("{} empty (unknown) values left out", dropped));
  }
  WarnOnTypeA(r);
  WarnOnGimbalLock(tag, q, w, window, window + n, r);
}

}  // namespace

Result<SessionTypeA> EvaluateSessionTypeA(const Session& session,
                                          const SessionTypeAOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError("invalid options: " + why);
  if (Status s = CheckSelection(session, options); !s.ok()) return s.error();
  SessionTypeA out;
  const Selection selection = Select(session, options, &out);
  if (Status s = CheckWindowNotEmpty(session, options.window, selection.tags, &out); !s.ok()) {
    return s.error();
  }
  if (options.window.settle_auto) DetectTransients(selection, options, &out);
  for (size_t k = 0; k < selection.tags.size(); ++k) {
    TagTypeA& t = out.tags[k];
    for (QuantityTypeA& r : t.quantities) r.window_begin = t.window.begin;
    if (!options.window.settle_auto) continue;
    CutSettled(*selection.tags[k], selection.source[k], options.window, &t);
  }
  for (size_t k = 0; k < selection.tags.size(); ++k) {
    FillWindowTimes(*selection.tags[k], &out.tags[k].window);
  }

  // Evaluate every (tag, quantity) on all cores.
  const std::vector<Job> jobs = JobsOf(selection, out);
  internal::ParallelFor(jobs.size(), options.threads, [&](size_t j) {
    const Job& job = jobs[j];
    const Tag& tag = *selection.tags[job.tag];
    TagTypeA& t = out.tags[job.tag];
    EvaluateQuantity(tag, tag.quantities[job.quantity], t.window, options, &t.quantities[job.slot]);
  });
  return out;
}

}  // namespace metro
