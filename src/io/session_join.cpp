// JoinSessionsOnTime runs these stages, in this order:
//
//   check   CheckDisjoint                no quantity in two sessions
//   tags    JoinTag: NearestSamples,     per tag of the first session: the nearest sample of
//           ZipMatched                   every other within half its period; the samples
//                                        all of them matched, zipped
//   finish  (driver)                     unmatched counts, columns, an empty join refused
#include "metro/io/session_join.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace metro {
namespace {

// A tag's time on the join's clock: exact ns when `exact` (as a double only for the
// distance, which is then an exact integer below 2^53 ns, some 104 days), else t_s.
double TimeAt(const Tag& tag, size_t i, bool exact) {
  return exact ? static_cast<double>(tag.t_ns[i]) : tag.t_s[i];
}

// Median interval of a tag, in the join's clock unit (ns when exact, else s).
double MedianInterval(const Tag& tag, bool exact) {
  std::vector<double> dt;
  for (size_t i = 1; i < tag.size(); ++i) {
    dt.push_back(exact ? static_cast<double>(tag.t_ns[i]) - static_cast<double>(tag.t_ns[i - 1])
                       : tag.t_s[i] - tag.t_s[i - 1]);
  }
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  return dt[dt.size() / 2];
}

// ---- JoinSessionsOnTime's stages ----------------------------------------------------------

constexpr size_t kNone = std::numeric_limits<size_t>::max();

// No quantity in two sessions.
Status CheckDisjoint(const std::vector<Session>& parts) {
  for (size_t a = 0; a < parts.size(); ++a) {
    for (size_t b = a + 1; b < parts.size(); ++b) {
      for (const Tag& ta : parts[a].tags) {
        const Tag* tb = parts[b].FindTag(ta.sensor);
        if (tb == nullptr) continue;
        for (const Quantity& q : ta.quantities) {
          if (tb->Find(q.name) != nullptr) {
            return MakeError(fmt::format(
                "{} and {} both have {} of sensor {}: a join needs each quantity from one "
                "file (rename one with --column)",
                parts[a].path, parts[b].path, q.name, ta.sensor));
          }
        }
      }
    }
  }
  return Status::Ok();
}

// Per sample of `base`, the index of the nearest sample of `other` within half its median
// period (or kNone). Ties go to the earlier.
std::vector<size_t> NearestSamples(const Tag& base, const Tag& other, bool exact) {
  std::vector<size_t> match(base.size(), kNone);
  const double half = MedianInterval(other, exact) / 2.0;
  size_t j = 0;
  for (size_t i = 0; i < base.size(); ++i) {
    const double t = TimeAt(base, i, exact);
    while (j + 1 < other.size() && TimeAt(other, j + 1, exact) <= t) ++j;
    // Candidates j (at or before t) and j + 1 (after t); ties go to the earlier.
    size_t best = j;
    double gap = std::fabs(TimeAt(other, j, exact) - t);
    if (j + 1 < other.size()) {
      const double after = std::fabs(TimeAt(other, j + 1, exact) - t);
      if (after < gap) {
        best = j + 1;
        gap = after;
      }
    }
    if (gap <= half) match[i] = best;
  }
  return match;
}

// The base tag's samples that every other session's tag matched, with all their quantities;
// the samples each session left unmatched counted in summary->unmatched.
Tag ZipMatched(const std::vector<Session>& parts, const Tag& base,
               const std::vector<const Tag*>& tags, const std::vector<std::vector<size_t>>& match,
               bool exact, JoinSummary* summary) {
  Tag tag;
  tag.sensor = base.sensor;
  std::vector<std::vector<bool>> used(parts.size());
  for (size_t p = 0; p < parts.size(); ++p) {
    if (tags[p] == nullptr) continue;
    used[p].assign(tags[p]->size(), false);
    for (const Quantity& q : tags[p]->quantities) {
      tag.quantities.push_back(Quantity{q.name, q.unit, q.origin, {}});
    }
  }
  for (size_t i = 0; i < base.size(); ++i) {
    bool all = true;
    for (size_t p = 1; p < parts.size(); ++p) {
      all = all && (tags[p] == nullptr || match[p][i] != kNone);
    }
    if (!all) continue;
    tag.t_s.push_back(base.t_s[i]);
    if (exact) tag.t_ns.push_back(base.t_ns[i]);
    tag.line.push_back(base.line[i]);
    size_t k = 0;
    for (size_t p = 0; p < parts.size(); ++p) {
      if (tags[p] == nullptr) continue;
      const size_t j = match[p][i];
      used[p][j] = true;
      for (const Quantity& q : tags[p]->quantities)
        tag.quantities[k++].values.push_back(q.values[j]);
    }
  }
  for (size_t p = 0; p < parts.size(); ++p) {
    if (tags[p] == nullptr) continue;
    summary->unmatched[p] += std::count(used[p].begin(), used[p].end(), false);
  }
  return tag;
}

// The joined tag of base's sensor.
Result<Tag> JoinTag(const std::vector<Session>& parts, const Tag& base, bool exact,
                    JoinSummary* summary) {
  // For every other session: its tag and per base sample the index of the matched sample
  // (or kNone).
  std::vector<std::vector<size_t>> match(parts.size(), std::vector<size_t>(base.size(), kNone));
  std::vector<const Tag*> tags(parts.size(), nullptr);
  tags[0] = &base;
  for (size_t i = 0; i < base.size(); ++i) match[0][i] = i;
  for (size_t p = 1; p < parts.size(); ++p) {
    const Tag* other = parts[p].FindTag(base.sensor);
    tags[p] = other;
    if (other == nullptr) continue;
    if (other->size() < 2) {
      return MakeError(parts[p].path, 0,
                       fmt::format("sensor {} has {} sample(s): a join needs a sample period",
                                   base.sensor, other->size()));
    }
    match[p] = NearestSamples(base, *other, exact);
  }
  return ZipMatched(parts, base, tags, match, exact, summary);
}

}  // namespace

Result<Session> JoinSessionsOnTime(const std::vector<Session>& parts, JoinSummary* summary) {
  if (parts.size() < 2) return MakeError("joining on time needs two sessions or more");
  *summary = JoinSummary{};
  bool exact = true;
  for (const Session& s : parts) {
    for (const Tag& t : s.tags) exact = exact && t.t_ns.size() == t.t_s.size();
  }
  if (Status s = CheckDisjoint(parts); !s.ok()) return s.error();
  Session out;
  out.path = parts[0].path;
  out.format = parts[0].format;
  out.input = parts[0].input;
  for (const Session& s : parts) {
    int64_t samples = 0;
    for (const Tag& t : s.tags) samples += static_cast<int64_t>(t.size());
    summary->samples.push_back(samples);
    summary->unmatched.push_back(0);
    out.sha256 += (out.sha256.empty() ? "" : "+") + s.sha256;
  }
  for (const Tag& base : parts[0].tags) {
    Result<Tag> joined = JoinTag(parts, base, exact, summary);
    if (!joined.ok()) return joined.error();
    Tag& tag = joined.value();
    tag.counts.frames = tag.counts.fresh = static_cast<int64_t>(tag.size());
    summary->rows += static_cast<int64_t>(tag.size());
    out.rows += static_cast<int64_t>(tag.size());
    if (tag.size() > 0) out.tags.push_back(std::move(tag));
  }
  // Tags only the other sessions have cannot be joined to the base: all unmatched.
  for (size_t p = 1; p < parts.size(); ++p) {
    for (const Tag& t : parts[p].tags) {
      if (parts[0].FindTag(t.sensor) == nullptr) {
        summary->unmatched[p] += static_cast<int64_t>(t.size());
      }
    }
  }
  for (const Tag& t : out.tags) {
    for (const Quantity& q : t.quantities) {
      if (std::find(out.columns.begin(), out.columns.end(), q.name) == out.columns.end()) {
        out.columns.push_back(q.name);
      }
    }
  }
  if (out.tags.empty()) {
    return MakeError(
        fmt::format("no sample of {} has a sample of every other file within half "
                    "a sample period: do the files share a clock?",
                    parts[0].path));
  }
  return out;
}

}  // namespace metro
