#include "io/columns.hpp"

#include <array>

namespace metro::internal {
namespace {

struct Known {
  std::string_view name;
  ColumnRole role;
  std::string_view unit;
  std::string_view family;
  bool allow_empty;
};

constexpr std::array<Known, 31> kKnown = {{
    {"t_s", ColumnRole::kTime, "s", "", false},
    {"sensor", ColumnRole::kSensor, "", "", false},
    {"qw", ColumnRole::kQuantity, "1", "quat", false},
    {"qx", ColumnRole::kQuantity, "1", "quat", false},
    {"qy", ColumnRole::kQuantity, "1", "quat", false},
    {"qz", ColumnRole::kQuantity, "1", "quat", false},
    {"yaw_deg", ColumnRole::kQuantity, "deg", "", false},
    {"pitch_deg", ColumnRole::kQuantity, "deg", "", false},
    {"roll_deg", ColumnRole::kQuantity, "deg", "", false},
    {"ax_g", ColumnRole::kQuantity, "g", "accel_g", false},
    {"ay_g", ColumnRole::kQuantity, "g", "accel_g", false},
    {"az_g", ColumnRole::kQuantity, "g", "accel_g", false},
    {"ax_mps2", ColumnRole::kQuantity, "m/s^2", "accel_mps2", false},
    {"ay_mps2", ColumnRole::kQuantity, "m/s^2", "accel_mps2", false},
    {"az_mps2", ColumnRole::kQuantity, "m/s^2", "accel_mps2", false},
    {"ax_lsb", ColumnRole::kQuantity, "LSB", "accel_lsb", false},
    {"ay_lsb", ColumnRole::kQuantity, "LSB", "accel_lsb", false},
    {"az_lsb", ColumnRole::kQuantity, "LSB", "accel_lsb", false},
    {"gx_dps", ColumnRole::kQuantity, "deg/s", "gyro_dps", false},
    {"gy_dps", ColumnRole::kQuantity, "deg/s", "gyro_dps", false},
    {"gz_dps", ColumnRole::kQuantity, "deg/s", "gyro_dps", false},
    {"gx_rads", ColumnRole::kQuantity, "rad/s", "gyro_rads", false},
    {"gy_rads", ColumnRole::kQuantity, "rad/s", "gyro_rads", false},
    {"gz_rads", ColumnRole::kQuantity, "rad/s", "gyro_rads", false},
    {"gx_lsb", ColumnRole::kQuantity, "LSB", "gyro_lsb", false},
    {"gy_lsb", ColumnRole::kQuantity, "LSB", "gyro_lsb", false},
    {"gz_lsb", ColumnRole::kQuantity, "LSB", "gyro_lsb", false},
    {"temp_c", ColumnRole::kQuantity, "degC", "", false},
    {"table_rate_dps", ColumnRole::kQuantity, "deg/s", "", true},
    {"table_angle_deg", ColumnRole::kQuantity, "deg", "", true},
    {"payload_hex", ColumnRole::kText, "", "", false},
}};

struct Suffix {
  std::string_view suffix;
  std::string_view unit;
};
constexpr std::array<Suffix, 12> kSuffixes = {{{"_s", "s"},
                                               {"_deg", "deg"},
                                               {"_rad", "rad"},
                                               {"_g", "g"},
                                               {"_mps2", "m/s^2"},
                                               {"_lsb", "LSB"},
                                               {"_dps", "deg/s"},
                                               {"_rads", "rad/s"},
                                               {"_c", "degC"},
                                               {"_hz", "Hz"},
                                               {"_m", "m"},
                                               {"_v", "V"}}};

bool EndsWith(std::string_view s, std::string_view suffix) {
  return s.size() > suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

ColumnInfo FromKnown(const Known& k) {
  return ColumnInfo{k.role, std::string(k.unit), std::string(k.family), k.allow_empty};
}

}  // namespace

ColumnInfo ClassifyColumn(std::string_view name) {
  for (const Known& k : kKnown) {
    if (k.name == name) return FromKnown(k);
  }
  ColumnInfo info;
  info.role = ColumnRole::kUnknown;
  for (const Suffix& s : kSuffixes) {
    if (EndsWith(name, s.suffix)) {
      info.unit = std::string(s.unit);
      break;
    }
  }
  return info;
}

bool IsValidColumnName(std::string_view name) {
  if (name.empty() || !(name[0] >= 'a' && name[0] <= 'z')) return false;
  for (char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) return false;
  }
  return true;
}

}  // namespace metro::internal
