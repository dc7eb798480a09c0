// Private: the registry of canonical session.csv columns.
#pragma once

#include <string>
#include <string_view>

namespace metro::internal {

enum class ColumnRole {
  kTime,      // t_s
  kSensor,    // sensor
  kQuantity,  // a known numeric quantity
  kText,      // a known text column (payload_hex)
  kUnknown,   // not in the registry
};

struct ColumnInfo {
  ColumnRole role = ColumnRole::kUnknown;
  std::string unit;          // For known quantities; the suffix's unit for unknown ones.
  std::string family;        // "accel_g", "gyro_dps", "quat", ... ; empty if none.
  bool allow_empty = false;  // An empty field means "unknown" (NaN).
};

ColumnInfo ClassifyColumn(std::string_view name);

// True if `name` is a legal column name: [a-z][a-z0-9_]*.
bool IsValidColumnName(std::string_view name);

}  // namespace metro::internal
