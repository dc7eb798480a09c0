// Private declarations shared by the session loaders.
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/io/session_io.hpp"

namespace metro::internal {

Result<Session> LoadSessionCsv(const std::string& path, const LoadOptions& options);
Result<Session> LoadReceiverCapture(const std::string& path, const LoadOptions& options);

// Adds a text column to the tag, or, for an unknown column whose every value is a finite
// number, a numeric Quantity with origin kUnknown.
void AddTextOrUnknownColumn(const std::string& name, bool unknown, const std::string& unit,
                            std::vector<std::string> values, Tag* tag);

// Adds yaw_deg, pitch_deg, roll_deg (origin kDerived) from qw..qz when the tag has the
// quaternion and none of the three angles.
void DeriveEulerIfAbsent(Tag* tag);

}  // namespace metro::internal
