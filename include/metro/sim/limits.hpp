// What the simulators accept (docs/simulator.md, "Limits"): every session they write is
// bounded, whatever the options.
#pragma once

#include <fmt/format.h>

#include <string>

namespace metro {

// Length of a simulated session.
inline constexpr double kSimMaxDurationS = 1e6;  // 11.6 days.
// session.csv sample rate and the reference log's rate.
inline constexpr double kSimMaxRateHz = 1e4;
// Receiver frame period: the central's DELTAT is a 16-bit count of its 32768 Hz clock.
inline constexpr double kSimMinFramePeriodS = 1e-3;
inline constexpr double kSimMaxFramePeriodS = 65535.0 / 32768.0;
// Observations in all (tags x samples): about 70 GB of session.csv.
inline constexpr double kSimMaxObservations = 1e9;
// Rotation table: plateaus per sweep, and the step between them.
inline constexpr double kSimMinTableStepDeg = 1e-3;
inline constexpr int kSimMaxTablePlateaus = 10000;

// The sample rate (0: one sample per receiver frame) and the receiver frame period within
// the limits above; otherwise false with the reason in *why. Both simulators call it.
inline bool SamplingWithinLimits(double rate_hz, double frame_period_s, std::string* why) {
  if (!(rate_hz >= 0.0 && rate_hz <= kSimMaxRateHz)) {
    *why =
        fmt::format("rate_hz must be in [0, {:g}] Hz (0: one sample per receiver frame), got {:g}",
                    kSimMaxRateHz, rate_hz);
    return false;
  }
  if (!(frame_period_s >= kSimMinFramePeriodS && frame_period_s <= kSimMaxFramePeriodS)) {
    *why = fmt::format("frame_period_s must be in [{:g}, {:g}] s, got {:g}", kSimMinFramePeriodS,
                       kSimMaxFramePeriodS, frame_period_s);
    return false;
  }
  return true;
}

}  // namespace metro
