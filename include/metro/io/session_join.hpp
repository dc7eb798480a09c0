// Joining the per-sensor files of one recording (Sensor Logger's Gyroscope.csv and
// Accelerometer.csv, say) into one session on time.
//
// The rule (docs/formats.md, "Joining files"): the first session is the time base. For
// each tag (by sensor number) and each of its samples at time t, every other session's
// sample of the same tag nearest in time is taken (an exact tie: the earlier one) when it
// lies within half that session's median sample period of t; a base sample for which some
// other session has no sample that near is left out. Times are compared as exact integer
// nanoseconds when every session has them (Tag::t_ns, epoch clocks of the same device),
// else as t_s (the files must then share their time origin). Nothing is interpolated.
#pragma once

#include <cstdint>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct JoinSummary {
  // Per input session, in order: its samples, and those that went into no joined row.
  std::vector<int64_t> samples;
  std::vector<int64_t> unmatched;
  int64_t rows = 0;  // Joined rows, all tags.
};

// Errors: fewer than two sessions, a quantity that two sessions both have, a session with
// fewer than 2 samples of a tag (no sample period).
Result<Session> JoinSessionsOnTime(const std::vector<Session>& parts, JoinSummary* summary);

}  // namespace metro
