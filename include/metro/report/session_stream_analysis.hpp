// The main job on a record too long to hold (issue #38 step 2): `characterize SESSION
// --type-a [--allan] --stream`. The session is read once, in groups of rows (io/
// session_stream.hpp); each selected quantity, its times and lines go to spill files on disk;
// then each quantity is evaluated from its spill in chunks (EvaluateTypeAChunked,
// EstimateSamplePeriodChunked, ComputeAllanChunked). Memory: a group of rows plus a few MB per
// quantity being evaluated, whatever the length.
//
// The numbers equal the in-memory path's (Type A to the last bit, Allan deviations to
// 1e-12), except what cannot be streamed, which is refused or named in the report, never
// guessed: settle detection and explicit windows (refused: they need the whole record or are
// not implemented here), plot series (named in input.notes), a lattice AR fit or a Zhang
// cut-off beyond 2^19 lags (type_a.hpp), wrapping angles and empty values (the quantity's
// error), gaps in the time grid and estimators other than oadev and ohdev (the quantity's
// allan error), and a --budget (refused).
#pragma once

#include <string>

#include "metro/report/session_analysis.hpp"

namespace metro {

// Options as AnalyzeSession's; the result's `session` holds no rows.
SessionAnalysis AnalyzeSessionStreamed(const std::string& path,
                                       const SessionAnalysisOptions& options);

}  // namespace metro
