// RunBatch runs these stages, in this order:
//
//   output dir  PrepareOutputDir                options, the directory created and locked
//   inputs      WithoutOwnOutputs,              the sessions and their report names
//               BatchReportNames
//   sessions    MakeSessionJobs, RunSession     each session analysed and written, in parallel
//   summary     Accumulate, AddSessionEntries,  per (sensor, quantity) and per tag across the
//               QuantityRows, TagRows           sessions; the summary's table
//   write       WriteSummary                    summary.json and summary.txt, both or neither
#include "metro/report/batch.hpp"

#include <fmt/format.h>
#include <glob.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>

#include "core/parallel.hpp"
#include "metro/core/angles.hpp"
#include "metro/core/file.hpp"
#include "metro/core/rounding.hpp"
#include "metro/core/terminal_text.hpp"
#include "metro/core/version.hpp"
#include "metro/io/columns.hpp"
#include "metro/report/html_report.hpp"
#include "metro/stats/circular.hpp"

namespace metro {

namespace fs = std::filesystem;

namespace {

bool IsPattern(const std::string& s) { return s.find_first_of("*?[") != std::string::npos; }

// One tag's quantity in one session, kept for the summary.
struct QuantityResult {
  int sensor = 0;
  std::string tag_name;
  std::string quantity;
  std::string unit;
  double mean = 0.0;
  double u_mean = 0.0;
  double n = 0.0;
  double n_eff = 0.0;
};

// One tag's receiver frame counts in one session.
struct TagResult {
  int sensor = 0;
  std::string tag_name;
  int64_t frames = 0, fresh = 0, stale = 0, never = 0;
};

struct SessionResults {
  std::vector<QuantityResult> quantities;
  std::vector<TagResult> tags;
  // NoFreshPacketWarnings and the analyses that produced nothing, prefixed with the session.
  std::vector<std::string> warnings;
};

SessionResults ExtractResults(const SessionReport& report, const std::string& input) {
  SessionResults results;
  results.warnings = NoFreshPacketWarnings(report, input + ": ");
  std::vector<QuantityResult>& out = results.quantities;
  for (const SensorReport& s : report.sensors) {
    TagResult t;
    t.sensor = static_cast<int>(s.sensor);
    t.tag_name = s.name;
    t.frames = s.frames;
    t.fresh = s.fresh;
    t.stale = s.stale;
    t.never = s.never;
    results.tags.push_back(t);
    for (const QuantityReport& q : s.quantities) {
      if (!q.type_a) continue;
      const TypeAReport& a = *q.type_a;
      QuantityResult r;
      r.sensor = static_cast<int>(s.sensor);
      r.tag_name = s.name;
      r.quantity = q.name;
      r.unit = q.unit;
      r.mean = a.mean;
      // metro's recommended u of the mean; reports from before it had only Zhang's.
      r.u_mean = a.has_u_mean ? a.u_mean : a.std_of_mean_autocorr;
      r.n = static_cast<double>(a.n);
      r.n_eff = a.n_eff;
      out.push_back(std::move(r));
    }
  }
  return results;
}

// "x.report.json" -> "x.report.html".
std::string BatchPagePath(const std::string& report_path) {
  fs::path p(report_path);
  return p.replace_extension(".html").string();
}

// Angles are pooled on the circle: a unit of dimension angle (deg, rad).
bool IsAngleUnit(const std::string& unit) {
  const Unit* u = UnitBySymbol(unit);
  return u != nullptr && u->dimension == Dimension::kAngle && u->to_si > 0.0;
}

// A batch's own outputs in its folder: never sessions.
bool IsBatchOutputName(const std::string& name) {
  const std::string report = ".report.json";
  return name == "summary.json" || name == "summary.txt" || name == kBatchLockName ||
         (name.size() > report.size() &&
          name.compare(name.size() - report.size(), report.size(), report) == 0);
}

// `inputs` without the files this batch writes into `output_dir` (left from an earlier run
// into the same folder: `batch DIR -o DIR`), each named in out->skipped.
std::vector<std::string> WithoutOwnOutputs(const std::vector<std::string>& inputs,
                                           const std::string& output_dir, BatchSummary* out) {
  std::vector<std::string> kept;
  for (const std::string& in : inputs) {
    const fs::path p(in);
    std::error_code ec;
    const fs::path parent = p.has_parent_path() ? p.parent_path() : fs::path(".");
    if (IsBatchOutputName(p.filename().string()) && fs::equivalent(parent, output_dir, ec)) {
      out->skipped.push_back(
          fmt::format("skipping {}: written by batch into its output directory", in));
      continue;
    }
    kept.push_back(in);
  }
  return kept;
}

// Why `path` cannot be read as a session ("" if it can): a symlink that leads nowhere, a
// directory, a FIFO (reading it would wait for a writer), a device or a socket.
std::string NotASessionFile(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    const int err = errno;
    struct stat link {};
    if (::lstat(path.c_str(), &link) == 0 && S_ISLNK(link.st_mode)) {
      std::error_code ec;
      const fs::path target = fs::read_symlink(path, ec);
      return fmt::format("a symlink to {} ({}): fix or remove the link",
                         ec ? std::string("?") : target.string(), std::strerror(err));
    }
    return fmt::format("cannot open: {}", std::strerror(err));
  }
  if (S_ISREG(st.st_mode)) return "";
  if (S_ISDIR(st.st_mode)) return "is a directory, not a session file";
  if (S_ISFIFO(st.st_mode)) return "is a FIFO, not a session file (batch reads named files)";
  return "is not a regular file (a device or a socket): batch reads session files";
}

}  // namespace

Result<FileLock> LockBatchDirectory(const std::string& output_dir) {
  const std::string path = (fs::path(output_dir) / kBatchLockName).string();
  Result<FileLockAttempt> attempt = TryLockFile(path);
  if (!attempt.ok()) return MakeError(output_dir, 0, attempt.error().message);
  if (attempt.value().lock) return Result<FileLock>(std::move(*attempt.value().lock));
  const std::string& who = attempt.value().holder;
  return MakeError(
      output_dir, 0,
      fmt::format("the output directory is in use by another batch ({}): wait for it to "
                  "finish or give another -o",
                  who.empty() ? "its lock file " + path : EscapeControlChars(who)));
}

bool BatchOptions::IsValid(std::string* why) const {
  if (output_dir.empty()) {
    *why = "batch: no output directory (-o DIR)";
    return false;
  }
  if (jobs < 0) {
    *why = fmt::format("batch: --jobs {} must be >= 0 (0: all cores)", jobs);
    return false;
  }
  return analysis.IsValid(why);
}

Result<std::vector<std::string>> ExpandBatchInputs(const std::vector<std::string>& arguments,
                                                   std::vector<std::string>* skipped) {
  if (arguments.empty()) return MakeError("batch: no session files, directories or patterns");
  std::set<std::string> files;
  auto skip = [skipped](const std::string& path, const std::string& why) {
    if (skipped != nullptr) skipped->push_back(fmt::format("skipping {}: {}", path, why));
  };
  for (const std::string& arg : arguments) {
    std::error_code ec;
    size_t found = 0;
    if (fs::is_directory(arg, ec)) {
      for (const fs::directory_entry& e : fs::directory_iterator(arg, ec)) {
        const std::string ext = e.path().extension().string();
        if (ext != ".csv" && ext != ".txt") continue;
        // Every *.csv and *.txt entry is a session, whatever it is: a symlink is followed,
        // and one that leads nowhere, a FIFO or a directory fails as its own session with
        // the reason (RunBatch), never silently left out.
        files.insert(e.path().string());
        ++found;
      }
      if (ec) return MakeError(arg, 0, fmt::format("cannot list the directory: {}", ec.message()));
      if (found == 0) return MakeError(arg, 0, "directory has no *.csv or *.txt session files");
    } else if (IsPattern(arg) && !fs::exists(fs::symlink_status(arg, ec))) {
      glob_t g{};
      const int rc = ::glob(arg.c_str(), 0, nullptr, &g);
      if (rc == 0) {
        for (size_t i = 0; i < g.gl_pathc; ++i) {
          if (fs::is_directory(g.gl_pathv[i], ec)) {
            skip(g.gl_pathv[i], "a directory (name it to read its *.csv and *.txt files)");
            continue;
          }
          files.insert(g.gl_pathv[i]);
          ++found;
        }
      }
      ::globfree(&g);
      if (found == 0) return MakeError(arg, 0, "pattern matches no file");
    } else {
      if (!fs::exists(fs::symlink_status(arg, ec))) return MakeError(arg, 0, "no such file");
      files.insert(arg);
    }
  }
  return std::vector<std::string>(files.begin(), files.end());
}

std::vector<std::string> BatchReportNames(const std::vector<std::string>& inputs) {
  std::map<std::string, int> stem_count;
  for (const std::string& in : inputs) ++stem_count[fs::path(in).stem().string()];
  std::vector<std::string> names;
  for (const std::string& in : inputs) {
    const std::string stem = fs::path(in).stem().string();
    if (stem_count[stem] > 1) {
      std::error_code ec;
      const fs::path absolute = fs::absolute(in, ec);
      const std::string key = ec ? in : absolute.lexically_normal().string();
      names.push_back(fmt::format("{}-{}.report.json", stem, Sha256Hex(key).substr(0, 8)));
    } else {
      names.push_back(stem + ".report.json");
    }
  }
  return names;
}

namespace {

// ---- output directory ---------------------------------------------------------------------

// The options checked, the output directory created and locked for this run (the lock goes
// with the descriptor); else out->error.
std::optional<FileLock> PrepareOutputDir(const BatchOptions& options, BatchSummary* out) {
  std::string why;
  if (!options.IsValid(&why)) {
    out->error = MakeError(why);
    return std::nullopt;
  }
  std::error_code ec;
  fs::create_directories(options.output_dir, ec);
  if (ec || !fs::is_directory(options.output_dir, ec)) {
    out->error = MakeError(options.output_dir, 0,
                           fmt::format("cannot create the output directory: {}", ec.message()));
    return std::nullopt;
  }
  Result<FileLock> lock = LockBatchDirectory(options.output_dir);
  if (!lock.ok()) {
    out->error = lock.error();
    return std::nullopt;
  }
  return std::move(lock).value();
}

// ---- sessions -----------------------------------------------------------------------------

// What one session's job needs besides its index.
struct SessionJobs {
  const std::vector<std::string>& inputs;
  const std::vector<std::string>& names;  // Report file names (BatchReportNames).
  const BatchOptions& options;
  SessionAnalysisOptions analysis;  // One thread per session.
  // Every input's identity: no report is written over one (through links).
  std::set<std::pair<dev_t, ino_t>> input_ids;
};

SessionJobs MakeSessionJobs(const std::vector<std::string>& inputs,
                            const std::vector<std::string>& names, const BatchOptions& options) {
  SessionJobs jobs{inputs, names, options, options.analysis, {}};
  jobs.analysis.load.threads = 1;
  jobs.analysis.type_a.threads = 1;
  jobs.analysis.allan_options.allan.threads = 1;
  jobs.analysis.allan_csv = false;
  for (const std::string& in : inputs) {
    struct stat st {};
    if (::stat(in.c_str(), &st) == 0) jobs.input_ids.insert({st.st_dev, st.st_ino});
  }
  return jobs;
}

// Session i: analysed, its report (and page) written; *item says how it went, *results and
// *hash hold what the summary needs when it went well.
void RunSession(const SessionJobs& jobs, size_t i, BatchItem* item, SessionResults* results,
                std::string* hash) {
  const std::vector<std::string>& inputs = jobs.inputs;
  const BatchOptions& options = jobs.options;
  item->input = inputs[i];
  const std::string report_path = (fs::path(options.output_dir) / jobs.names[i]).string();
  std::string refused = NotASessionFile(inputs[i]);
  struct stat report_st {};
  if (refused.empty() && ::stat(report_path.c_str(), &report_st) == 0 &&
      jobs.input_ids.count({report_st.st_dev, report_st.st_ino}) > 0) {
    refused = fmt::format(
        "its report {} is one of the inputs: refusing to overwrite an input; "
        "move that file or choose another -o",
        report_path);
  }
  const SessionAnalysis a =
      refused.empty() ? AnalyzeSession(inputs[i], jobs.analysis) : SessionAnalysis{};
  if (!refused.empty()) {
    item->error = MakeError(inputs[i], 0, refused);
    return;
  }
  if (!a.ok) {
    item->error = a.error;
    item->input_error = a.input_error;
    return;
  }
  item->report_path = report_path;
  std::string page;
  if (options.session_pages) {
    item->page_path = BatchPagePath(report_path);
    Result<std::string> html = RenderSessionAnalysisHtml(a);
    if (html.ok()) {
      page = std::move(html).value();
    } else {
      item->error = html.error();
      item->input_error = false;
    }
  }
  const std::string json = ToJson(a.report) + "\n";
  Status s = !item->error.message.empty() ? Status(item->error)
             : options.session_pages
                 ? WriteFilesAtomically({{item->report_path, json}, {item->page_path, page}})
                 : WriteFileAtomically(item->report_path, json);
  if (!s.ok()) {
    item->error = s.error();
    item->input_error = false;
    item->report_path.clear();
    item->page_path.clear();
    return;
  }
  item->ok = true;
  *hash = a.session.sha256;
  *results = ExtractResults(a.report, inputs[i]);
  // An analysis asked for that produced nothing for a quantity (issue #21).
  for (const std::string& f : a.failures) results->warnings.push_back(inputs[i] + ": " + f);
}

// ---- accumulation -------------------------------------------------------------------------

// One (sensor, quantity) across sessions.
struct Accumulated {
  std::string tag_name, unit;
  std::vector<double> means;
  double worst_ratio = std::numeric_limits<double>::infinity();
  std::string worst_session;
  std::set<std::string> units;
};
// Receiver counts of one tag across sessions.
struct TagAccumulated {
  std::string tag_name;
  size_t sessions = 0, sessions_without_fresh = 0;
  int64_t frames = 0, fresh = 0, stale = 0, never = 0;
};
// The sessions' results gathered, in (sensor, quantity) and sensor order.
struct Totals {
  std::map<std::pair<int, std::string>, Accumulated> by_quantity;
  std::map<int, TagAccumulated> by_tag;
  std::vector<std::string> warnings;
};

Totals Accumulate(const std::vector<std::string>& inputs,
                  const std::vector<SessionResults>& results) {
  Totals totals;
  for (size_t i = 0; i < inputs.size(); ++i) {
    for (const std::string& w : results[i].warnings) totals.warnings.push_back(w);
    for (const TagResult& t : results[i].tags) {
      TagAccumulated& acc = totals.by_tag[t.sensor];
      if (acc.tag_name.empty()) acc.tag_name = t.tag_name;
      ++acc.sessions;
      acc.frames += t.frames;
      acc.fresh += t.fresh;
      acc.stale += t.stale;
      acc.never += t.never;
      if (t.frames > 0 && t.fresh == 0) ++acc.sessions_without_fresh;
    }
  }
  for (size_t i = 0; i < inputs.size(); ++i) {
    for (const QuantityResult& r : results[i].quantities) {
      Accumulated& acc = totals.by_quantity[{r.sensor, r.quantity}];
      if (acc.tag_name.empty()) acc.tag_name = r.tag_name;
      acc.unit = r.unit;
      acc.units.insert(r.unit);
      acc.means.push_back(r.mean);
      const double ratio = r.n > 0 ? r.n_eff / r.n : std::nan("");
      if (ratio < acc.worst_ratio) {
        acc.worst_ratio = ratio;
        acc.worst_session = inputs[i];
      }
    }
  }
  return totals;
}

// One entry per session in the summary (out->summary.sessions); counts out->failed.
void AddSessionEntries(const std::vector<std::string>& names,
                       const std::vector<std::string>& hashes,
                       const std::vector<SessionResults>& results, BatchSummary* out) {
  for (size_t i = 0; i < out->items.size(); ++i) {
    const BatchItem& item = out->items[i];
    BatchSessionEntry s;
    s.input = item.input;
    s.ok = item.ok;
    if (item.ok) {
      s.sha256 = hashes[i];
      s.report = names[i];
      if (!item.page_path.empty()) s.page = fs::path(item.page_path).filename().string();
      s.tags.emplace();
      for (const TagResult& t : results[i].tags) {
        s.tags->push_back({t.sensor, t.tag_name, t.frames, t.fresh, t.stale, t.never,
                           t.frames > 0 && t.fresh == 0});
      }
      s.quantities.emplace();
      for (const QuantityResult& r : results[i].quantities) {
        s.quantities->push_back({r.sensor, r.tag_name, r.quantity, r.unit, r.mean, r.u_mean, r.n});
      }
    } else {
      ++out->failed;
      s.error = item.error.ToString();
      s.input_error = item.input_error;
    }
    out->summary.sessions.push_back(std::move(s));
  }
}

// ---- tables -------------------------------------------------------------------------------

// One record per line: tag names, quantities, units and file names are data (a session
// file named "s\nFAILED x.csv" must not print a line of its own), escaped field by field.
std::string Text(const std::string& data) { return EscapeControlChars(data); }

// Per (sensor, quantity): the session means pooled (summary->quantities) and the table rows.
std::string QuantityRows(const Totals& totals, BatchSummaryReport* summary) {
  std::string table;
  for (const auto& [key, acc] : totals.by_quantity) {
    const size_t n = acc.means.size();
    const bool circular = acc.units.size() == 1 && IsAngleUnit(acc.unit);
    double mean = 0.0, std_of_means = std::nan("");
    CircularStatistics circle;
    if (circular) {
      // Angles on the circle (Mardia & Jupp 2000): +179.95 and -179.95 deg pool to 180.
      const double deg_per_unit = UnitBySymbol(acc.unit)->to_si * 180.0 / M_PI;
      std::vector<double> deg;
      for (double m : acc.means) deg.push_back(m * deg_per_unit);
      circle = CircularStatisticsDeg(deg);
      mean = circle.mean_deg / deg_per_unit;
      std_of_means = circle.sample_std_deg / deg_per_unit;
    } else {
      double sum = 0.0;
      for (double m : acc.means) sum += m;
      mean = sum / static_cast<double>(n);
      double ss = 0.0;
      for (double m : acc.means) ss += (m - mean) * (m - mean);
      // JCGM 100:2008 4.2.2: experimental standard deviation of the session means.
      if (n >= 2) std_of_means = std::sqrt(ss / static_cast<double>(n - 1));
    }
    BatchQuantitySummary q;
    q.sensor = key.first;
    q.name = acc.tag_name;
    q.quantity = key.second;
    q.unit = acc.unit;
    q.sessions = static_cast<int64_t>(n);
    q.statistics = circular ? "circular" : "linear";
    q.mean_of_means = mean;
    if (n >= 2) q.std_of_means = std_of_means;
    if (circular) q.resultant_length = circle.resultant_length;
    q.worst_n_eff_ratio = acc.worst_ratio;
    q.worst_n_eff_session = acc.worst_session;
    if (acc.units.size() > 1) q.warning = "sessions disagree on the unit of this quantity";
    if (circular && !std::isfinite(mean)) {
      q.warning = "the session means cancel on the circle (R = 0): no mean direction";
    }
    summary->quantities.push_back(std::move(q));
    const bool has_std = n >= 2 && std::isfinite(std_of_means);
    const RoundedResult r = std::isfinite(mean)
                                ? RoundForStatement(mean, has_std ? std_of_means : 0.0)
                                : RoundedResult{"-", "-"};
    table += fmt::format("{:>6} {:<16} {:<18} {:>8} {:>4} {:>16} {:>12} {:>10.3f}\n", key.first,
                         Text(acc.tag_name), Text(key.second), Text(acc.unit), n, r.value,
                         has_std ? r.uncertainty : "-", acc.worst_ratio);
  }
  return table;
}

// Per tag: receiver counts; packet_loss_ratio = (stale + never) / frames (docs/formats.md).
std::string TagRows(const Totals& totals, BatchSummaryReport* summary) {
  summary->tags.emplace();
  std::string tag_table;
  for (const auto& [sensor, acc] : totals.by_tag) {
    const bool receiver = acc.frames > 0;
    const double loss =
        receiver ? static_cast<double>(acc.stale + acc.never) / static_cast<double>(acc.frames)
                 : 0.0;
    summary->tags->push_back({sensor, acc.tag_name, static_cast<int64_t>(acc.sessions), acc.frames,
                              acc.fresh, acc.stale, acc.never, loss,
                              static_cast<int64_t>(acc.sessions_without_fresh)});
    if (!receiver) continue;
    tag_table += fmt::format(
        "{:>6} {:<16} {:>8} {:>10} {:>10} {:>10} {:>10} {:>8.2f} %{}\n", sensor, Text(acc.tag_name),
        acc.sessions, acc.frames, acc.fresh, acc.stale, acc.never, 100.0 * loss,
        acc.sessions_without_fresh > 0
            ? fmt::format("  no fresh packet in {} session(s)", acc.sessions_without_fresh)
            : "");
  }
  return tag_table;
}

// summary.json and summary.txt, both or neither.
void WriteSummary(const BatchOptions& options, BatchSummary* out) {
  const fs::path dir(options.output_dir);
  const std::string summary_json = ToJson(out->summary) + "\n";
  if (Status s = WriteFilesAtomically({{(dir / "summary.json").string(), summary_json},
                                       {(dir / "summary.txt").string(), out->table}});
      !s.ok()) {
    out->error = s.error();
    return;
  }
  out->ok = out->failed == 0;
}

}  // namespace

BatchSummary RunBatch(const std::vector<std::string>& all_inputs, const BatchOptions& options) {
  BatchSummary out;
  // The folder is this run's until it returns.
  const std::optional<FileLock> lock = PrepareOutputDir(options, &out);
  if (!lock) return out;
  const std::vector<std::string> inputs = WithoutOwnOutputs(all_inputs, options.output_dir, &out);
  const std::vector<std::string> names = BatchReportNames(inputs);
  out.items.resize(inputs.size());
  std::vector<SessionResults> results(inputs.size());
  std::vector<std::string> hashes(inputs.size());
  const SessionJobs jobs = MakeSessionJobs(inputs, names, options);
  std::mutex progress_mutex;
  size_t done = 0;
  internal::ParallelFor(inputs.size(), options.jobs, [&](size_t i) {
    RunSession(jobs, i, &out.items[i], &results[i], &hashes[i]);
    if (options.on_progress) {
      std::lock_guard<std::mutex> guard(progress_mutex);
      options.on_progress(++done, inputs.size());
    }
  });

  // Summary per tag and quantity across sessions, in (sensor, quantity) order.
  const Totals totals = Accumulate(inputs, results);
  BatchSummaryReport& summary = out.summary;
  summary.tool = {kToolName, kVersion};
  summary.warnings = totals.warnings;
  summary.output_dir = options.output_dir;
  summary.sessions_total = static_cast<int64_t>(inputs.size());
  AddSessionEntries(names, hashes, results, &out);
  summary.sessions_failed = static_cast<int64_t>(out.failed);
  std::string table;
  for (const std::string& w : totals.warnings) table += Text(w) + "\n";
  table += fmt::format("{} sessions, {} failed\n", inputs.size(), out.failed);
  table += fmt::format("{:>6} {:<16} {:<18} {:>8} {:>4} {:>16} {:>12} {:>10}\n", "sensor", "tag",
                       "quantity", "unit", "n", "mean of means", "std of means", "worst n_eff/n");
  table += QuantityRows(totals, &summary);
  const std::string tag_table = TagRows(totals, &summary);
  if (!tag_table.empty()) {
    table += fmt::format("\n{:>6} {:<16} {:>8} {:>10} {:>10} {:>10} {:>10} {:>10}\n", "sensor",
                         "tag", "sessions", "frames", "fresh", "stale", "never", "loss");
    table += tag_table;
  }
  for (const BatchItem& item : out.items) {
    if (!item.ok) {
      table += fmt::format("FAILED {}: {}\n", Text(item.input), Text(item.error.ToString()));
    }
  }
  // Tag names and file names in the table are data: escaped, so that `cat summary.txt` cannot
  // drive a terminal.
  out.table = EscapeControlCharsKeepLines(table);
  WriteSummary(options, &out);
  return out;
}

}  // namespace metro
