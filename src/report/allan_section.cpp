#include "metro/report/allan_section.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "metro/core/rounding.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/io/columns.hpp"
#include "metro/noise/allan_report.hpp"
#include "metro/report/console_text.hpp"

namespace metro {
namespace {

// Position of each sample on the grid of period tau0: k = round((t - t_first) / tau0), from
// the exact integer times when the file had them. Errors: two samples in one grid slot (a
// clock that does not fit one grid).
Result<std::vector<int64_t>> GridIndices(const Tag& tag, size_t begin, size_t end, double tau0_s,
                                         const std::string& path) {
  std::vector<int64_t> index(end - begin);
  const bool exact = tag.t_ns.size() == tag.t_s.size();
  for (size_t k = begin; k < end; ++k) {
    const double dt_s = exact ? static_cast<double>(tag.t_ns[k] - tag.t_ns[begin]) * 1e-9
                              : tag.t_s[k] - tag.t_s[begin];
    index[k - begin] = std::llround(dt_s / tau0_s);
    if (k > begin && index[k - begin] <= index[k - begin - 1]) {
      return MakeError(path, tag.line[k],
                       fmt::format("this sample and the one at line {} fall on one slot of the "
                                   "{} s sample grid: the clock does not fit one grid; expected "
                                   "timestamps near multiples of the sample period",
                                   tag.line[k - 1], tau0_s));
    }
  }
  return index;
}

// The curve of a record with missing grid samples, by `policy`; *gaps describes what was
// missing and what was done about it (report key allan.gaps, docs/noise.md "Gaps").
Result<AllanCurve> CurveThroughGaps(const std::vector<double>& rate,
                                    const std::vector<int64_t>& index, double tau0_s,
                                    const SessionAllanOptions& options, AllanGapsReport* gaps) {
  const int64_t grid = index.back() + 1;
  const int64_t n = static_cast<int64_t>(rate.size());
  const int64_t missing = grid - n;
  const double fraction = static_cast<double>(missing) / static_cast<double>(grid);
  gaps->policy = AllanGapPolicyName(options.gaps);
  gaps->grid_samples = grid;
  gaps->missing_samples = missing;
  gaps->missing_fraction = fraction;
  if (fraction > options.max_missing_fraction) {
    return MakeError(fmt::format(
        "{} of the {} samples of the record's time grid are missing ({:.1f} %, more than {:.0f} "
        "%): an Allan deviation would rest on a minority of the record; expected a record with "
        "fewer gaps, or a window (--from-s/--to-s) around a complete stretch",
        missing, grid, 100.0 * fraction, 100.0 * options.max_missing_fraction));
  }
  if (options.gaps == AllanGapPolicy::kSkip) {
    std::vector<double> on_grid(static_cast<size_t>(grid), 0.0);
    std::vector<uint8_t> present(static_cast<size_t>(grid), 0);
    for (size_t k = 0; k < rate.size(); ++k) {
      on_grid[static_cast<size_t>(index[k])] = rate[k];
      present[static_cast<size_t>(index[k])] = 1;
    }
    return ComputeAllanWithGaps(on_grid, present, tau0_s, options.allan);
  }
  // kSplit: the longest run of consecutive grid slots.
  size_t best_begin = 0, best_length = 0, stretches = 0;
  for (size_t k = 0, begin = 0; k <= rate.size(); ++k) {
    if (k == rate.size() || (k > begin && index[k] != index[k - 1] + 1)) {
      ++stretches;
      if (k - begin > best_length) {
        best_begin = begin;
        best_length = k - begin;
      }
      begin = k;
    }
  }
  gaps->stretches = static_cast<int64_t>(stretches);
  gaps->analysed_first_sample = static_cast<int64_t>(best_begin);
  gaps->analysed_samples = static_cast<int64_t>(best_length);
  const auto b = static_cast<ptrdiff_t>(best_begin);
  const auto e = static_cast<ptrdiff_t>(best_begin + best_length);
  return ComputeAllan(std::vector<double>(rate.begin() + b, rate.begin() + e), tau0_s,
                      options.allan);
}

}  // namespace

const char* AllanGapPolicyName(AllanGapPolicy policy) {
  switch (policy) {
    case AllanGapPolicy::kSkip:
      return "skip";
    case AllanGapPolicy::kSplit:
      return "split";
    case AllanGapPolicy::kRefuse:
      return "refuse";
  }
  return "?";
}

Result<AllanGapPolicy> ParseAllanGapPolicy(const std::string& text) {
  for (AllanGapPolicy p :
       {AllanGapPolicy::kSkip, AllanGapPolicy::kSplit, AllanGapPolicy::kRefuse}) {
    if (text == AllanGapPolicyName(p)) return p;
  }
  return MakeError(fmt::format("--gaps '{}': expected skip, split or refuse", text));
}

namespace {

// The curve of one quantity from the session in memory: its window's sample period, then the
// curve, through the gaps by `options.gaps` when samples are missing.
AllanQuantityCurve CurveInMemory(const Session& session, const TagTypeA& t, const QuantityTypeA& q,
                                 const SessionAllanOptions& options) {
  AllanQuantityCurve out;
  const Tag* tag = session.FindTag(t.sensor);
  METRO_CHECK(tag != nullptr);
  const Quantity* values = tag->Find(q.name);
  const auto b = static_cast<ptrdiff_t>(t.window.begin);
  const auto e = static_cast<ptrdiff_t>(t.window.end);
  // The window's rates: the column itself when the window is all of it (no copy).
  std::vector<double> window_copy;
  const bool whole = b == 0 && static_cast<size_t>(e) == values->values.size();
  if (!whole) window_copy.assign(values->values.begin() + b, values->values.begin() + e);
  const std::vector<double>& rate = whole ? values->values : window_copy;
  // tau0 from exact integer differences when the file's time was integer (t_ns).
  SamplePeriodOptions period_options = options.period;
  period_options.allow_gaps = options.gaps != AllanGapPolicy::kRefuse;
  // The window's times and lines read in place (no copies of 10^7-sample columns).
  const size_t count = t.window.end - t.window.begin;
  const uint32_t* line = tag->line.data() + b;
  out.period = tag->t_ns.size() == tag->t_s.size()
                   ? EstimateSamplePeriodNs(tag->t_ns.data() + b, line, count, period_options)
                   : EstimateSamplePeriod(tag->t_s.data() + b, line, count, period_options);
  if (!out.period.ok()) return out;
  if (out.period.value().missing_samples == 0) {
    out.curve = ComputeAllan(rate, out.period.value().tau0_s, options.allan);
  } else {
    Result<std::vector<int64_t>> index =
        GridIndices(*tag, t.window.begin, t.window.end, out.period.value().tau0_s, session.path);
    if (index.ok()) {
      out.gaps = AllanGapsReport{};
      out.curve =
          CurveThroughGaps(rate, index.value(), out.period.value().tau0_s, options, &*out.gaps);
    } else {
      out.curve = index.error();
    }
  }
  return out;
}

// The report's allan block of one quantity from its curve (or why there is none).
void AddCurve(const TagTypeA& t, const QuantityTypeA& q, AllanQuantityCurve made,
              const SessionAllanOptions& options, const std::string& path, QuantityReport* jq,
              std::string* csv, AllanSectionSummary* summary) {
  auto failed = [&](const std::string& reason) {
    summary->failures.push_back(fmt::format("sensor {} {}: {}", t.sensor, q.name, reason));
  };
  if (!made.period.ok()) {
    Error err = made.period.error();
    err.file = path;
    if (options.gaps == AllanGapPolicy::kRefuse && err.message.find("gap") != std::string::npos) {
      err.message += " (--gaps refuse; --gaps skip analyses through them)";
    }
    jq->allan = AllanReport{};
    jq->allan->error = err.ToString();
    failed(err.ToString());
    return;
  }
  if (!made.curve.ok()) {
    jq->allan = AllanReport{};
    jq->allan->error = made.curve.error().ToString();
    jq->allan->gaps = made.gaps;
    failed(made.curve.error().ToString());
    return;
  }
  const AllanCurve& curve = made.curve.value();
  ++summary->analysed;
  NoiseFit noise_fit;
  AllanReport allan = AllanReportOfCurve(curve, options.fit, q.unit, &noise_fit);
  const SamplePeriod& p = made.period.value();
  allan.sample_period = {p.tau0_s,           p.rate_hz,
                         p.mean_dt_s,        p.jitter_rms_s,
                         p.max_abs_jitter_s, static_cast<int64_t>(p.missing_samples),
                         p.warnings};
  allan.gaps = made.gaps;
  // A rejected or untested noise model is said on stderr and in the report (issue #36).
  if (allan.model_check && !(allan.model_check->tested && !allan.model_check->rejected)) {
    jq->warnings.push_back(allan.model_check->summary);
  }
  jq->allan = std::move(allan);
  jq->allan_type_a_link =
      MakeAllanTypeALink(curve, noise_fit, t.window.t_last_s - t.window.t_first_s);
  if (csv != nullptr) {
    *csv += fmt::format("# sensor {} {}\n", t.sensor, q.name);
    *csv += AllanCurveCsv(curve, q.unit);
  }
}

}  // namespace

Result<AllanSectionSummary> AddAllanToReport(const Session& session, const SessionTypeA& type_a,
                                             const SessionAllanOptions& options,
                                             SessionReport* report, std::string* csv) {
  return AddAllanToReportFrom(
      type_a, options, session.path,
      [&](const TagTypeA& t, const QuantityTypeA& q) {
        return CurveInMemory(session, t, q, options);
      },
      report, csv);
}

Result<AllanSectionSummary> AddAllanToReportFrom(const SessionTypeA& type_a,
                                                 const SessionAllanOptions& options,
                                                 const std::string& path,
                                                 const AllanCurveSource& source,
                                                 SessionReport* report, std::string* csv) {
  std::string why;
  if (!options.allan.IsValid(&why)) return MakeError("invalid --allan options: " + why);
  AllanSectionSummary summary;
  std::vector<SensorReport>& sensors = report->sensors;
  for (size_t k = 0; k < type_a.tags.size(); ++k) {
    const TagTypeA& t = type_a.tags[k];
    SensorReport& jtag = sensors[k];
    for (const QuantityTypeA& q : t.quantities) {
      const bool wanted = options.quantities.empty()
                              ? IsRateQuantity(q.name)
                              : std::find(options.quantities.begin(), options.quantities.end(),
                                          q.name) != options.quantities.end();
      if (!wanted) continue;
      ++summary.requested;
      QuantityReport* jq = jtag.Find(q.name);
      METRO_CHECK(jq != nullptr);
      AddCurve(t, q, source(t, q), options, path, jq, csv, &summary);
    }
  }
  if (summary.requested == 0) {
    return MakeError(path, 0,
                     "--allan: no rate quantity (gyroscope or accelerometer column) in the "
                     "window; name one with --quantity");
  }
  return summary;
}

std::string AllanSummaryTable(const SessionReport& report) {
  std::string out;
  auto term = [](const AllanNoiseTermReport& t) -> std::string {
    if (!t.supported || !std::isfinite(t.value) || !std::isfinite(t.u)) return "-";
    return ConciseNotation(t.value, t.u) + " " + t.unit;
  };
  for (const SensorReport& s : report.sensors) {
    for (const QuantityReport& q : s.quantities) {
      if (!q.allan || !q.allan->ok()) continue;
      const AllanReport& allan = *q.allan;
      if (out.empty()) {
        out = fmt::format(
            "\nAllan deviation ({}; IEEE 952 terms fitted, value(u)):\n{:>6} {:<18} {:<28} "
            "{:<28} {:<28} {}\n",
            allan.estimator, "sensor", "quantity", "N (white noise)", "B (bias instability)",
            "K (rate random walk)", "minimum");
      }
      std::string minimum = "-";
      if (q.allan_type_a_link && std::isfinite(q.allan_type_a_link->allan_min_dev)) {
        const AllanTypeALink& link = *q.allan_type_a_link;
        minimum = fmt::format("{} {} at {:.3g} s{}", ConsoleNumber(link.allan_min_dev),
                              EscapeControlChars(q.unit), link.allan_min_tau_s,
                              link.allan_min_at_end ? " (last tau)" : "");
      }
      out += fmt::format("{:>6} {:<18} {:<28} {:<28} {:<28} {}\n", s.sensor,
                         EscapeControlChars(q.name), term(allan.term(NoiseTerm::kRandomWalk)),
                         term(allan.term(NoiseTerm::kBiasInstability)),
                         term(allan.term(NoiseTerm::kRateRandomWalk)), minimum);
    }
  }
  if (!out.empty()) {  // Which is which among the field's names (issue #40).
    out +=
        "  N = angle (gyroscope) or velocity (accelerometer) random walk = Kalibr's "
        "*_noise_density (continuous, two-sided PSD N^2; a datasheet's one-sided density is "
        "sqrt(2) N); K = Kalibr's *_random_walk; in SI with characterize noise-export "
        "(docs/noise.md section 9)\n";
  }
  return out;
}

}  // namespace metro
