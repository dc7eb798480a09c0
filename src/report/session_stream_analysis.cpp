// AnalyzeSessionStreamed (session_stream_analysis.hpp), in stages:
//   CheckStreamable  the options the streaming mode has
//   SpillGroups      the session read in groups; each selected quantity's values, times and
//                    lines appended to its tag's spill files
//   EvaluateSpilled  Type A of every (tag, quantity) from its spill, on all cores
//   the report as AnalyzeSession makes it, the Allan curves from the spills
#include "metro/report/session_stream_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "core/parallel.hpp"
#include "metro/core/angles.hpp"
#include "metro/core/spill_file.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/io/columns.hpp"
#include "metro/io/session_stream.hpp"
#include "metro/report/batch.hpp"
#include "metro/report/settle_report.hpp"
#include "metro/report/type_a_report.hpp"
#include "metro/report/u_mean_evidence.hpp"

namespace metro {
namespace {

struct QuantitySpill {
  std::string name, unit;
  QuantityOrigin origin = QuantityOrigin::kFile;
  SpillColumn<double> values;
  int64_t non_finite = 0;
  double max_abs = 0.0;
  // Angles that wrap at +-180 deg are unwrapped as they are appended, as UnwrapDegInPlace
  // unwraps a column in memory: the last unwrapped value, the offset, the jumps.
  bool unwrap = false;
  bool any = false;
  double last = 0.0;
  double offset = 0.0;
  int jumps = 0;
  std::vector<double> unwrapped;  // This group's values, unwrapped.
};

// UnwrapDegInPlace (core/angles.hpp) continued across groups.
const std::vector<double>& Unwrap(const std::vector<double>& values, QuantitySpill* q) {
  q->unwrapped.assign(values.begin(), values.end());
  for (size_t i = 0; i < q->unwrapped.size(); ++i) {
    double& a = q->unwrapped[i];
    if (q->any) {
      const double raw_step = (a + q->offset) - q->last;
      if (raw_step > 180.0 || raw_step < -180.0) {
        q->offset -= 360.0 * std::round(raw_step / 360.0);
        ++q->jumps;
      }
      a += q->offset;
    }
    q->any = true;
    q->last = a;
  }
  return q->unwrapped;
}

struct TagSpill {
  int sensor = 0;
  size_t n = 0;
  bool integer_time = false;
  SpillColumn<double> t_s;
  SpillColumn<int64_t> t_ns;
  SpillColumn<uint32_t> line;
  double t_first_s = 0.0, t_last_s = 0.0;
  uint32_t first_line = 0, last_line = 0;
  std::vector<std::unique_ptr<QuantitySpill>> quantities;
  QuantitySpill* Find(const std::string& name) {
    for (auto& q : quantities) {
      if (q->name == name) return q.get();
    }
    return nullptr;
  }
};

Status CheckStreamable(const SessionAnalysisOptions& options) {
  const WindowOptions& w = options.type_a.window;
  if (w.settle_auto) {
    return MakeError(
        "--settle auto needs the whole record (MSER-5 over all of it): not "
        "available in streaming mode; run without --stream");
  }
  if (w.skip_samples != 0 || w.skip_seconds != 0.0 || w.from_s || w.to_s) {
    return MakeError(
        "windows (--skip, --skip-s, --from-s, --to-s) are not available in "
        "streaming mode yet; run without --stream");
  }
  if (!options.budget_path.empty()) {
    return MakeError("--budget is not available in streaming mode; run without --stream");
  }
  return Status::Ok();
}

bool Selected(const std::vector<std::string>& wanted, const std::string& name) {
  return wanted.empty() || std::find(wanted.begin(), wanted.end(), name) != wanted.end();
}

// Appends one group's rows to the spills (tags and quantities as they first appear).
Status AppendGroup(const Session& group, const SessionTypeAOptions& options,
                   std::map<int, TagSpill>* spills) {
  for (const Tag& tag : group.tags) {
    if (!options.sensors.empty() && std::find(options.sensors.begin(), options.sensors.end(),
                                              tag.sensor) == options.sensors.end()) {
      continue;
    }
    auto [it, fresh] = spills->try_emplace(tag.sensor);
    TagSpill& s = it->second;
    if (fresh) {
      s.sensor = tag.sensor;
      s.integer_time = tag.t_ns.size() == tag.t_s.size();
      if (Status st = s.t_s.Open(); !st.ok()) return st;
      if (Status st = s.t_ns.Open(); !st.ok()) return st;
      if (Status st = s.line.Open(); !st.ok()) return st;
      s.t_first_s = tag.t_s.front();
      s.first_line = tag.line.front();
    }
    for (const Quantity& q : tag.quantities) {
      if (!Selected(options.quantities, q.name)) continue;
      QuantitySpill* qs = s.Find(q.name);
      if (qs == nullptr) {
        if (s.n > 0) {
          return MakeError(group.path, tag.line.front(),
                           fmt::format("sensor {}'s column {} first appears here, after {} rows "
                                       "without it: not available in streaming mode",
                                       tag.sensor, q.name, s.n));
        }
        s.quantities.push_back(std::make_unique<QuantitySpill>());
        qs = s.quantities.back().get();
        qs->name = q.name;
        qs->unit = q.unit;
        qs->origin = q.origin;
        qs->unwrap = IsWrappingAngle(q.name);
        if (Status st = qs->values.Open(); !st.ok()) return st;
      }
      const std::vector<double>& values = qs->unwrap ? Unwrap(q.values, qs) : q.values;
      for (double v : values) {
        if (!std::isfinite(v)) {
          ++qs->non_finite;
        } else {
          qs->max_abs = std::max(qs->max_abs, std::abs(v));
        }
      }
      if (Status st = qs->values.Append(values.data(), values.size()); !st.ok()) return st;
    }
    if (Status st = s.t_s.Append(tag.t_s.data(), tag.t_s.size()); !st.ok()) return st;
    if (s.integer_time) {
      if (Status st = s.t_ns.Append(tag.t_ns.data(), tag.t_ns.size()); !st.ok()) return st;
    }
    if (Status st = s.line.Append(tag.line.data(), tag.line.size()); !st.ok()) return st;
    s.n += tag.size();
    s.t_last_s = tag.t_s.back();
    s.last_line = tag.line.back();
  }
  return Status::Ok();
}

ChunkReader ReaderOf(const SpillColumn<double>& column) {
  return
      [&column](size_t begin, size_t count, double* out) { return column.Read(begin, count, out); };
}

// The tag's Type A block as EvaluateSessionTypeA makes it (whole record, no settle).
TagTypeA MakeTag(const TagSpill& s) {
  TagTypeA t;
  t.sensor = s.sensor;
  t.counts.frames = t.counts.fresh = static_cast<int64_t>(s.n);
  t.window.n_total = s.n;
  t.window.begin = 0;
  t.window.end = s.n;
  t.window.t_first_s = s.t_first_s;
  t.window.t_last_s = s.t_last_s;
  t.window.first_line = s.first_line;
  t.window.last_line = s.last_line;
  for (const auto& q : s.quantities) {
    QuantityTypeA r;
    r.name = q->name;
    r.unit = q->unit;
    r.origin = q->origin;
    r.angle_handling = q->unwrap ? "unwrapped" : "linear";
    r.unwrap_jumps = q->jumps;
    t.quantities.push_back(std::move(r));
  }
  return t;
}

void EvaluateSpilled(std::map<int, TagSpill>& spills, const SessionTypeAOptions& options,
                     SessionTypeA* out) {
  struct Job {
    TagSpill* tag;
    QuantitySpill* quantity;
    QuantityTypeA* result;
  };
  std::vector<Job> jobs;
  for (auto& [sensor, s] : spills) {
    out->tags.push_back(MakeTag(s));
  }
  size_t k = 0;
  for (auto& [sensor, s] : spills) {
    TagTypeA& t = out->tags[k++];
    for (size_t q = 0; q < s.quantities.size(); ++q) {
      jobs.push_back({&s, s.quantities[q].get(), &t.quantities[q]});
    }
  }
  internal::ParallelFor(jobs.size(), options.threads, [&](size_t j) {
    const Job& job = jobs[j];
    QuantityTypeA& r = *job.result;
    if (job.quantity->non_finite > 0) {
      r.error = fmt::format(
          "{} empty (unknown) values: leaving them out is not available in "
          "streaming mode (run without --stream)",
          job.quantity->non_finite);
      return;
    }
    const ChunkReader read = ReaderOf(job.quantity->values);
    auto a = EvaluateTypeAChunked(read, job.tag->n, options.type_a);
    if (!a.ok()) {
      r.error = a.error().message;
      return;
    }
    r.ok = true;
    r.type_a = a.value();
    if (job.quantity->unwrap) r.type_a.mean = WrapDeg180(r.type_a.mean);
    WarnOnTypeA(&r);
    const QuantitySpill* pitch = job.tag->Find("pitch_deg");
    WarnOnGimbalLockFromMax(r.name, r.origin, pitch != nullptr ? pitch->max_abs : 0.0, &r);
  });
}

// The sample period and curve of one quantity from its tag's spills.
AllanQuantityCurve CurveFromSpill(const TagSpill& s, const QuantitySpill& q,
                                  const SessionAllanOptions& options) {
  AllanQuantityCurve out;
  TimeColumnReader time;
  if (s.integer_time) {
    time.t_ns = [&s](size_t begin, size_t count, int64_t* dst) {
      return s.t_ns.Read(begin, count, dst);
    };
  } else {
    time.t_s = [&s](size_t begin, size_t count, double* dst) {
      return s.t_s.Read(begin, count, dst);
    };
  }
  const LineColumnReader line = [&s](size_t begin, size_t count, uint32_t* dst) {
    return s.line.Read(begin, count, dst);
  };
  SamplePeriodOptions period_options = options.period;
  period_options.allow_gaps = options.gaps != AllanGapPolicy::kRefuse;
  out.period = EstimateSamplePeriodChunked(time, line, s.n, period_options);
  if (!out.period.ok()) return out;
  if (out.period.value().missing_samples > 0) {
    out.curve = MakeError(fmt::format(
        "{} samples are missing from the time grid: the Allan deviation through gaps is not "
        "available in streaming mode (run without --stream)",
        out.period.value().missing_samples));
    return out;
  }
  out.curve = ComputeAllanChunked(ReaderOf(q.values), static_cast<int64_t>(s.n),
                                  out.period.value().tau0_s, options.allan);
  return out;
}

}  // namespace

SessionAnalysis AnalyzeSessionStreamed(const std::string& path,
                                       const SessionAnalysisOptions& options) {
  SessionAnalysis out;
  auto fail = [&out](Error error, bool input_error) {
    out.ok = false;
    out.error = std::move(error);
    out.input_error = input_error;
    return std::move(out);
  };
  std::string why;
  if (!options.IsValid(&why)) return fail(MakeError(why), true);
  if (Status s = CheckStreamable(options); !s.ok()) return fail(s.error(), true);
  ProgressSink* progress = options.progress;
  LoadOptions load = options.load;
  if (progress != nullptr) {
    BeginLoadPhase(progress, path);
    load.on_bytes_parsed = [progress](int64_t n) { progress->Advance(n); };
  }
  std::map<int, TagSpill> spills;
  auto session = StreamSession(
      path, load, [&](Session& group) { return AppendGroup(group, options.type_a, &spills); },
      std::max<size_t>(options.stream_group_bytes, 1));
  if (!session.ok()) return fail(session.error(), true);
  out.session = std::move(session).value();
  for (auto& [sensor, s] : spills) {
    for (auto& q : s.quantities) {
      if (Status st = q->values.Finish(); !st.ok()) return fail(st.error(), false);
    }
    for (Status st : {s.t_s.Finish(), s.t_ns.Finish(), s.line.Finish()}) {
      if (!st.ok()) return fail(st.error(), false);
    }
  }
  if (spills.empty()) {
    return fail(MakeError(path, 0, "no observations of the selected sensors"), true);
  }
  if (progress != nullptr) progress->BeginPhase("Type A", kUncountedWork);
  EvaluateSpilled(spills, options.type_a, &out.type_a);
  out.session.input.notes.push_back(
      "streaming mode (--stream): the record was read once in groups of rows and each quantity "
      "evaluated from a spill file; plot series are not available in streaming mode");
  out.report = MakeSessionReport(out.session, out.type_a, options.type_a, options.registry);
  AddSettleToReport(out.session, out.type_a, options.type_a.window, &out.report);
  if (options.allan) {
    if (progress != nullptr) progress->BeginPhase("Allan deviation", kUncountedWork);
    Result<AllanSectionSummary> allan = AddAllanToReportFrom(
        out.type_a, options.allan_options, path,
        [&](const TagTypeA& t, const QuantityTypeA& q) {
          TagSpill& s = spills.at(t.sensor);
          return CurveFromSpill(s, *s.Find(q.name), options.allan_options);
        },
        &out.report, options.allan_csv ? &out.allan_csv : nullptr);
    if (!allan.ok()) return fail(allan.error(), true);
    for (const std::string& f : allan.value().failures) out.failures.push_back("--allan: " + f);
    out.nothing_produced = out.nothing_produced || allan.value().NothingProduced();
    ApplyAllanEvidenceToUMean(&out.type_a, &out.report);
  }
  out.table.clear();
  for (const std::string& w : NoFreshPacketWarnings(out.report)) {
    out.table += EscapeControlChars(w) + "\n";
  }
  out.table += TypeAReportTable(out.report);
  if (progress != nullptr) progress->Finish();
  out.ok = true;
  return out;
}

}  // namespace metro
