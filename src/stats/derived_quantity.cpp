#include "metro/stats/derived_quantity.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "metro/io/columns.hpp"

namespace metro {
namespace {

std::optional<std::string> Message(const Tag& tag, std::string_view name,
                                   const std::string& holder) {
  const std::vector<std::string> inputs = DerivationInputs(name);
  if (inputs.empty()) return std::nullopt;
  std::vector<std::string> present;
  for (const Quantity& q : tag.quantities) present.push_back(q.name);
  const std::vector<std::string> missing = MissingColumns(inputs, present);
  if (missing.empty() || missing.size() == inputs.size()) return std::nullopt;
  std::vector<std::string> held;
  for (const std::string& input : inputs) {
    if (std::find(missing.begin(), missing.end(), input) == missing.end()) held.push_back(input);
  }
  return fmt::format("{} is derived from {}; {} has {}; missing {}", name, fmt::join(inputs, ", "),
                     holder, fmt::join(held, ", "), fmt::join(missing, ", "));
}

}  // namespace

std::vector<std::string> DerivationInputs(std::string_view name) {
  if (name == "yaw_deg" || name == "pitch_deg" || name == "roll_deg") {
    return FamilyColumns(SensorKind::kQuaternion, nullptr);
  }
  return {};
}

std::optional<std::string> MissingDerivationInputs(const Tag& tag, std::string_view name) {
  return Message(tag, name, "the session");
}

std::optional<std::string> MissingDerivationInputs(const Session& session, std::string_view name) {
  for (const Tag& tag : session.tags) {
    std::optional<std::string> m =
        Message(tag, name,
                session.tags.size() == 1 ? std::string("the session")
                                         : fmt::format("sensor {}", tag.sensor));
    if (m) return m;
  }
  return std::nullopt;
}

}  // namespace metro
