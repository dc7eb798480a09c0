// Simulated rotation-table (position-table) sessions with known truth (docs/simulator.md,
// "Rotation-table sessions"), for the accuracy evaluation (docs/accuracy.md).
//
// The table turns one axis of the tag (`axis`: yaw, pitch or roll) through plateaus:
// start_deg, start_deg + step_deg, ..., end_deg (the up pass), then back down to start_deg
// (the down pass, the turning point visited once); `sweeps` such up-and-down passes. It
// dwells `dwell_s` on each plateau and moves between them at `move_rate_dps`. The table's
// own angle theta(t) [deg] is written as `table_angle_deg`, rounded to
// reference_resolution_deg (an encoder), continuously (also while moving: the table turns at
// move_rate_dps from one plateau to the next), wrapped into (-180, 180] with readout_wrap_180.
//
// The tag's angle of the turned axis (what its DMP reports), with d = +1 on a plateau reached
// by turning up (theta increasing), -1 when reached turning down, and 0 for the first one:
//   true(t)  = theta(t) + offset_deg + scale_error * theta(t)
//            + cos1_deg cos(theta) + sin1_deg sin(theta)        mounting misalignment
//            + d * hysteresis_deg / 2                            (up minus down = hysteresis)
//   tag(t)   = lag(true)(t) + e(t),  lag: first-order response with time constant lag_tau_s
//              (the DMP's settling after each move); e AR(1) with std noise_std_deg and lag-1
//              correlation noise_ar1 per 0.10013 s frame
// The two axes not turned sit at base_deg plus a mounting tilt that couples into them,
//   other_1 = base_1 + tilt_deg sin(theta),  other_2 = base_2 + tilt_deg cos(theta)
// (other_1/other_2 = pitch/roll for a yaw table, yaw/roll for pitch, yaw/pitch for roll),
// plus the same kind of AR(1) noise. The three angles are rounded to quantization_deg (the
// packets' 0.01 deg) and written as a quaternion w, x, y, z (sequence (1,2,3), angles.hpp).
// Zero offset, scale_error, harmonics, hysteresis and tilt mean a perfect tag.
//
// With a separate reference log the tag file carries no table column and the reference is
// written to its own `t_s,table_angle_deg` file at reference_rate_hz, its clock running
// reference_clock_offset_s ahead of the tag's (reference t_s = tag-clock t_s + offset).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "metro/accuracy/table_axis.hpp"
#include "metro/core/status.hpp"
#include "metro/io/receiver.hpp"
#include "metro/io/session.hpp"
#include "metro/sim/static_session.hpp"

namespace metro {

struct TableSimulationOptions {
  uint64_t seed = 1;
  int sensor = 2;
  TableAxis axis = TableAxis::kYaw;
  double start_deg = 0.0;
  double step_deg = 30.0;
  double end_deg = 330.0;
  int sweeps = 2;
  double dwell_s = 20.0;
  double move_rate_dps = 20.0;
  double rate_hz = 0.0;  // session.csv rate; 0: one sample per receiver frame.
  double frame_period_s = kReceiverFramePeriodS;
  // Truth of the tag's error.
  double offset_deg = 0.5;
  double scale_error = 0.002;  // deg/deg
  double cos1_deg = 0.3;
  double sin1_deg = -0.2;
  double hysteresis_deg = 0.15;
  double tilt_deg = 0.4;
  double base_deg[2] = {1.0, -2.0};  // The two axes not turned, in yaw, pitch, roll order.
  double noise_std_deg = 0.05;
  double noise_ar1 = 0.9;
  double lag_tau_s = 0.3;
  double quantization_deg = 0.01;
  double reference_resolution_deg = 0.001;
  double packet_loss = 0.02;
  // Separate reference log (SimulateTableSession's reference_sink).
  double reference_rate_hz = 20.0;
  double reference_clock_offset_s = 0.0;
  // The table reports signed angles, wrapped into (-180, 180] (many readouts do).
  bool readout_wrap_180 = false;
  // A pitch table may pass +-90 deg (the tag's Euler pitch then folds over); off: refused.
  bool pitch_through_90 = false;
  // One pass up only (no down pass: hysteresis is not measured); needs sweeps = 1.
  bool up_only = false;

  bool IsValid(std::string* why) const;
};

// What the simulator put in, for tests.
struct TablePlateauTruth {
  double reference_deg = 0.0;
  int direction = 0;       // +1 reached turning up, -1 turning down, 0 first plateau.
  double error_deg = 0.0;  // Systematic error of the turned axis on this plateau.
  double t_start_s = 0.0;  // Table stopped.
  double t_end_s = 0.0;    // Table starts moving again.
  double t_move_s = 0.0;   // The table left the previous plateau (= t_start_s for the first).
  double other_deg[2] = {0.0, 0.0};  // The two axes not turned (base + tilt), settled.
};

struct TableTruth {
  std::vector<TablePlateauTruth> plateaus;
  double duration_s = 0.0;
};

// Systematic error of the tag's turned axis at table angle theta_deg (the model above).
double TableErrorModelDeg(const TableSimulationOptions& options, double theta_deg, int direction);

// The truth as the sidecar JSON "metro.table-truth/1" (docs/simulator.md): the error model's
// parameters, lag, noise, clock offset, readout and every plateau with its true error.
std::string TableTruthJson(const TableSimulationOptions& options, const TableTruth& truth);

// Writes the tag session in `format` (kCsv: with `table_angle_deg` unless reference_sink is
// given; kReceiver: the capture, which has no room for the table) to `sink`, and the
// separate reference log (`t_s,table_angle_deg`) to `reference_sink` when it is set. A
// receiver capture needs a reference_sink.
Status SimulateTableSession(const TableSimulationOptions& options, SessionFormat format,
                            const TextSink& sink, const TextSink& reference_sink = nullptr,
                            TableTruth* truth = nullptr);

}  // namespace metro
