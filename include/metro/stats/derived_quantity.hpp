// Quantities metro derives on load rather than reads (io/session.hpp, docs/formats.md): the
// Euler angles yaw_deg, pitch_deg, roll_deg from the whole quaternion qw, qx, qy, qz (w
// first). A session may hold any subset of the quaternion's columns; with part of it no angle
// is derived, and a request for one by name (`--quantity yaw_deg`, a budget's session
// quantity, the accuracy evaluation's table axis) should say which columns are missing rather
// than only that the quantity is absent. This is the one place that message is written.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/io/session.hpp"

namespace metro {

// The columns `name` is derived from, in family order: {"qw", "qx", "qy", "qz"} for yaw_deg,
// pitch_deg and roll_deg; empty for a quantity metro does not derive.
std::vector<std::string> DerivationInputs(std::string_view name);

// When `name` is derived (DerivationInputs) and `tag` holds some but not all of its inputs:
//   "yaw_deg is derived from qw, qx, qy, qz; the session has qw, qx; missing qy, qz".
// nullopt when `name` is not derived, or the tag holds none or all of the inputs.
std::optional<std::string> MissingDerivationInputs(const Tag& tag, std::string_view name);

// The same for a session: the first tag holding part of the inputs. With more than one tag
// the message names it: "...; sensor 2 has qw, qx; missing qy, qz".
std::optional<std::string> MissingDerivationInputs(const Session& session, std::string_view name);

}  // namespace metro
