// Annotated segments: the static poses, table runs and rotations of a calibration record as
// the user marked them (start and end times), instead of the static detector.
//
// File (`calibrate fit --segments FILE`): CSV with a header naming the columns, in any order:
//   kind,start_s,end_s[,table_rate_dps][,input]
//   static,0.0,4.5
//   rotation,4.5,6.5
//   table,7.0,17.0,30
// kind is static, rotation or table (table needs table_rate_dps [deg/s], the table's signed
// rate); start_s and end_s are the record's own t_s (inclusive); input is the 1-based index of
// the SESSION argument the times refer to (default 1; needed only with several inputs).
// Blank lines and lines starting with '#' are skipped.
#pragma once

#include <string>
#include <vector>

#include "metro/calibration/segments.hpp"
#include "metro/core/status.hpp"

namespace metro {

struct AnnotatedSegment {
  SegmentKind kind = SegmentKind::kStatic;  // kStatic, kRotation or kTable.
  int input = 0;                            // 0-based input (piece) index.
  double start_s = 0;
  double end_s = 0;
  double table_rate_dps = 0;  // kTable only.
  int line = 0;               // Line of the file, for messages.
};

// Reads the file; errors carry file:line:column, what was expected and an example line.
Result<std::vector<AnnotatedSegment>> ReadSegmentsFile(const std::string& path);

// The segments of one record from the annotations for its input (`input.piece`): each
// annotation covers the samples with start_s <= t_s <= end_s; every static annotation is its own
// pose; rotations not annotated are the samples between consecutive static annotations (as the
// detector makes them). An annotation outside the record, with fewer than 2 samples, or
// overlapping another of the same kind is an error naming its line of `path`.
Result<SegmentationSummary> SegmentsFromAnnotations(const SegmentationInput& input,
                                                    const std::vector<AnnotatedSegment>& all,
                                                    const std::string& path);

}  // namespace metro
