#include "metro/uncertainty/session_resolver.hpp"

#include <fmt/format.h>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "metro/core/file.hpp"
#include "metro/io/columns.hpp"
#include "metro/stats/derived_quantity.hpp"

namespace metro {
namespace {

// "sensor 1 has no quantity yaw_deg", with the missing quaternion columns when the quantity
// is derived from a quaternion the tag holds part of.
Error NoQuantity(const Session& session, const SessionQuantityRef& ref) {
  std::string message = fmt::format("sensor {} has no quantity {}", ref.sensor, ref.quantity);
  const Tag* tag = session.FindTag(ref.sensor);
  if (tag != nullptr) {
    if (std::optional<std::string> why = MissingDerivationInputs(*tag, ref.quantity)) {
      message += ": " + *why;
    }
  }
  return MakeError(session.path, 0, message);
}

// The quantity's unit from its column suffix (io/columns.hpp) in metro/core/units.hpp
// syntax: io's "g" of accelerometer columns is standard gravity, which UDUNITS-2 (and a
// budget) writes g_n ("g" there is the gram).
std::string BudgetUnitOf(const std::string& quantity) {
  const ColumnInfo info = ClassifyColumn(quantity);
  if (info.unit == nullptr) return "";
  if (info.unit->dimension == Dimension::kAcceleration && info.unit->symbol == "g") return "g_n";
  return std::string(info.unit->symbol);
}

Result<TypeASummary> Summarize(const Session& session, const SessionQuantityRef& ref,
                               const TagTypeA& tag) {
  const std::string& path = session.path;
  const QuantityTypeA* q = nullptr;
  for (const QuantityTypeA& candidate : tag.quantities) {
    if (candidate.name == ref.quantity) q = &candidate;
  }
  if (q == nullptr) return NoQuantity(session, ref);
  if (!q->ok) {
    return MakeError(path, 0, fmt::format("sensor {} {}: {}", ref.sensor, ref.quantity, q->error));
  }
  const TypeAResult& a = q->type_a;
  if (!a.u_mean_available) {
    return MakeError(path, 0,
                     fmt::format("sensor {} {}: {}; expected a quantity that varies, or a Type B "
                                 "input for the readings' resolution instead of this session one",
                                 ref.sensor, ref.quantity, a.autocorr_note));
  }
  // metro's recommended u of the mean and its dof (type_a.hpp u_mean: the AR spectral
  // density at zero, raised by the stationarity and Allan checks; docs/type-a.md).
  TypeASummary s;
  s.mean = a.mean;
  s.u = a.u_mean;
  s.dof = std::max(1.0, a.u_mean_dof);
  s.n = a.n;
  s.unit = BudgetUnitOf(ref.quantity);
  s.note = fmt::format("Type A of {} sensor {} {}: n = {}, u = u_mean ({}), {:.1f} dof", path,
                       ref.sensor, ref.quantity, a.n, a.u_mean_method, a.u_mean_dof);
  return s;
}

Result<TypeASummary> EvaluateRef(const Session& session, const SessionQuantityRef& ref,
                                 const WindowOptions& window) {
  const Tag* tag = session.FindTag(ref.sensor);
  if (tag != nullptr && tag->Find(ref.quantity) == nullptr &&
      MissingDerivationInputs(*tag, ref.quantity)) {
    return NoQuantity(session, ref);
  }
  SessionTypeAOptions options;
  options.window = window;
  options.sensors = {ref.sensor};
  options.quantities = {ref.quantity};
  auto evaluated = EvaluateSessionTypeA(session, options);
  if (!evaluated.ok()) return evaluated.error();
  return Summarize(session, ref, evaluated.value().tags.at(0));
}

}  // namespace

SessionQuantityResolver MakeSessionQuantityResolver(const Session& session,
                                                    const SessionTypeA& evaluated,
                                                    WindowOptions window) {
  return [&session, &evaluated, window](const SessionQuantityRef& ref) -> Result<TypeASummary> {
    // The same file under another spelling is the evaluated session (its load options and
    // window), compared by the file's identity, not by the path's spelling (issue #39).
    if (!ref.session.empty() && !IsSameFile(ref.session, session.path)) {
      LoadOptions load;
      auto other = LoadSession(ref.session, load);
      if (!other.ok()) return other.error();
      return EvaluateRef(other.value(), ref, window);
    }
    for (const TagTypeA& tag : evaluated.tags) {
      if (tag.sensor != ref.sensor) continue;
      for (const QuantityTypeA& q : tag.quantities) {
        if (q.name == ref.quantity) return Summarize(session, ref, tag);
      }
    }
    return EvaluateRef(session, ref, window);
  };
}

SessionQuantityResolver MakeSessionQuantityResolver(std::string default_session, LoadOptions load,
                                                    WindowOptions window) {
  // Loaded sessions, found again by the file's identity (IsSameFile), so another spelling of
  // one file is not loaded twice.
  auto cache = std::make_shared<std::vector<std::pair<std::string, Session>>>();
  return [default_session = std::move(default_session), load, window,
          cache](const SessionQuantityRef& ref) -> Result<TypeASummary> {
    const std::string path = ref.session.empty() ? default_session : ref.session;
    if (path.empty()) {
      return MakeError(
          fmt::format("quantity {} names no session and none was given on the "
                      "command line",
                      ref.quantity));
    }
    for (const auto& [cached_path, session] : *cache) {
      if (IsSameFile(path, cached_path)) return EvaluateRef(session, ref, window);
    }
    auto loaded = LoadSession(path, load);
    if (!loaded.ok()) return loaded.error();
    cache->emplace_back(path, std::move(loaded).value());
    return EvaluateRef(cache->back().second, ref, window);
  };
}

}  // namespace metro
