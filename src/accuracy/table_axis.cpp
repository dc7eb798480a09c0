#include "metro/accuracy/table_axis.hpp"

namespace metro {

const char* TableAxisName(TableAxis axis) {
  switch (axis) {
    case TableAxis::kYaw:
      return "yaw";
    case TableAxis::kPitch:
      return "pitch";
    case TableAxis::kRoll:
      return "roll";
  }
  return "?";
}

const char* TableAxisQuantity(TableAxis axis) {
  switch (axis) {
    case TableAxis::kYaw:
      return "yaw_deg";
    case TableAxis::kPitch:
      return "pitch_deg";
    case TableAxis::kRoll:
      return "roll_deg";
  }
  return "?";
}

Result<TableAxis> ParseTableAxis(const std::string& name) {
  if (name == "yaw") return TableAxis::kYaw;
  if (name == "pitch") return TableAxis::kPitch;
  if (name == "roll") return TableAxis::kRoll;
  return MakeError("unknown table axis '" + name + "' (expected yaw, pitch or roll)");
}

}  // namespace metro
