// Type A evaluation of a whole session: every tag, every numeric quantity, in a window.
//
// Windows are applied per tag, in this order: skip the first `skip_samples` observations;
// skip observations earlier than the tag's first time + `skip_seconds`; keep
// from_s <= t_s <= to_s; then, with `settle_auto`, drop the start-up transient found by
// DetectSettleTransient (stats/settle.hpp): by default each quantity from its own settle
// point (QuantityTypeA::window_begin); with `settle_tag_wide` every quantity of the tag from
// the largest cut of its non-temperature quantities. A temperature (degC) never cuts the
// other quantities: a sensor's warm-up drift is not a transient of its rates or angles.
// The tag's AppliedWindow always carries that largest non-temperature cut (settle_driver
// names the quantity), so analyses that need one window per tag (the Allan deviation, the
// HTML time series) start where every rate and angle has settled.
//
// Angles that wrap at +-180 deg (yaw_deg, roll_deg, table_angle_deg) are unwrapped before
// the statistics (each step taken as the shortest turn) and the mean is wrapped back into
// (-180, 180]; the report says so ("angle_handling": "unwrapped").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/session.hpp"
#include "metro/stats/settle.hpp"
#include "metro/stats/type_a.hpp"

namespace metro {

struct WindowOptions {
  int64_t skip_samples = 0;
  double skip_seconds = 0.0;
  std::optional<double> from_s;
  std::optional<double> to_s;
  bool settle_auto = false;
  // With settle_auto: cut every quantity of a tag at the largest cut of its
  // non-temperature quantities (`--settle-scope tag`) instead of each at its own.
  bool settle_tag_wide = false;
  SettleOptions settle;

  bool IsValid(std::string* why) const;
};

struct SessionTypeAOptions {
  WindowOptions window;
  std::vector<int> sensors;             // Empty: every tag.
  std::vector<std::string> quantities;  // Empty: every numeric quantity.
  TypeAOptions type_a;
  int threads = 0;  // 0: all cores.

  bool IsValid(std::string* why) const;
};

struct AppliedWindow {
  size_t n_total = 0;         // Observations of the tag.
  size_t begin = 0;           // First observation kept (index).
  size_t end = 0;             // One past the last kept.
  size_t settle_samples = 0;  // Largest settle cut of a non-temperature quantity.
  bool settle_at_limit = false;
  std::string settle_driver;  // The quantity whose cut that is ("" when none).
  double t_first_s = 0.0;     // Times of the first and last kept observation.
  double t_last_s = 0.0;
  uint32_t first_line = 0;
  uint32_t last_line = 0;
  size_t n() const { return end - begin; }
};

// The observations of `tag` that the explicit window options keep (skip_samples,
// skip_seconds, from_s, to_s; settle_auto is not applied here). Only n_total, begin and
// end are set.
AppliedWindow ExplicitWindow(const Tag& tag, const WindowOptions& window);

struct QuantityTypeA {
  std::string name;
  std::string unit;
  QuantityOrigin origin = QuantityOrigin::kFile;
  bool ok = false;  // False: `error` says why there is no evaluation.
  std::string error;
  TypeAResult type_a;
  std::string angle_handling = "linear";  // or "unwrapped"
  int unwrap_jumps = 0;
  size_t settle_samples = 0;  // This quantity's own settle cut (settle_auto).
  SettleResult settle;        // Its detection (settle_auto; `fitted` false otherwise).
  size_t window_begin = 0;    // Index of the first observation evaluated (own window).
  std::vector<std::string> warnings;
};

struct TagTypeA {
  int sensor = 0;
  FrameCounts counts;
  AppliedWindow window;
  std::vector<QuantityTypeA> quantities;
  std::vector<std::string> warnings;
};

struct SessionTypeA {
  std::vector<TagTypeA> tags;
};

// Errors: an unknown --sensor or --quantity, invalid options.
Result<SessionTypeA> EvaluateSessionTypeA(const Session& session,
                                          const SessionTypeAOptions& options);

// The warnings EvaluateSessionTypeA adds to a quantity from its Type A result
// (autocorrelation, u_mean not available, drift), and the gimbal-lock warnings on pitch_deg,
// yaw_deg and roll_deg from the largest |pitch_deg| in the window; for evaluations made
// elsewhere (the streaming mode).
void WarnOnTypeA(QuantityTypeA* r);
void WarnOnGimbalLockFromMax(const std::string& name, QuantityOrigin origin,
                             double pitch_max_abs_deg, QuantityTypeA* r);

// True for quantities that wrap at +-180 deg.
bool IsWrappingAngle(const std::string& quantity_name);

}  // namespace metro
