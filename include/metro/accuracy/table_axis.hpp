// The tag axis a rotation table turns (docs/accuracy.md, "Input"). The accuracy evaluation
// reads the tag's angle of this axis (yaw_deg, pitch_deg or roll_deg, the Euler angles of
// sequence (1,2,3), core/angles.hpp) against the table's angle; the table simulator
// (sim/table_session.hpp) turns the same axis.
#pragma once

#include <string>

#include "metro/core/status.hpp"

namespace metro {

enum class TableAxis { kYaw = 0, kPitch = 1, kRoll = 2 };

// "yaw", "pitch", "roll".
const char* TableAxisName(TableAxis axis);
// The session quantity of an axis: "yaw_deg", "pitch_deg", "roll_deg".
const char* TableAxisQuantity(TableAxis axis);
// Parses "yaw" | "pitch" | "roll"; the error names the three valid axes.
Result<TableAxis> ParseTableAxis(const std::string& name);

}  // namespace metro
