// The input flags every command that loads a session shares: format, dialect mapping, time
// and raw-count scales (docs/formats.md). One definition, so the commands cannot drift.
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session_io.hpp"

namespace metro::apps {

struct LoadCliOptions {
  std::string format = "auto";
  std::vector<std::string> columns;  // --column 'SRC=DST', repeatable.
  std::string columns_file;          // --columns-file FILE: SRC=DST lines.
  std::string time = "header";       // --time header|receive (MCAP, ROS bags).
  std::string time_order = "sort";   // --time-order sort|refuse (MCAP, ROS bags, ULog).
  // --frame-period-s, --lenient, --rate-hz (a file without a time column), --accel-fs-g,
  // --gyro-fs-dps (raw counts scaled beside the counts) and --topic (ULog), bound to the
  // library's struct (its defaults); MakeLoadOptions copies these six fields.
  LoadOptions library;
};

// The library's load options for these flags (threads left as they are). Errors (a bad
// --column, an unreadable --columns-file) are usage errors.
Status MakeLoadOptions(const LoadCliOptions& o, LoadOptions* load);

}  // namespace metro::apps
