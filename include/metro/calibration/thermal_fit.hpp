// Bias versus temperature (issue #42 step 1, docs/thermal.md), per axis, from a static record:
//
//   b(T) = c_0 + c_1 x + ... + c_p x^p  [+ leg h / 2],   x = T - t_ref_c,
//   leg = +1 heating, -1 cooling (only when both legs are present; h = thermal hysteresis).
//
// c_0 = b0, c_1 = b1, c_2 = b2 of the blob (blob.hpp); c_3, c_4 beyond what it holds today.
// Samples are averaged in temperature bins (bin_width_c, per leg) and every bin weighs the same
// (uniform in temperature, not in time: a slow part of a ramp does not dominate). The fit is
// ordinary least squares on the bin means; covariance V = s^2 (X'X)^-1 with s^2 the residual
// variance on n_bins - n_params degrees of freedom (JCGM 100:2008 H.3.3-H.3.4; JCGM 100:2008
// 4.2.3 for type A). The order is chosen by nested F-tests of each order p = 2 .. max against
// p - 1, F = (RSS_{p-1} - RSS_p) / (RSS_p / nu_p) ~ F(1, nu_p) when c_p = 0: the highest order
// whose upper-tail probability is below alpha / (max - 1) (Bonferroni), else 1.
// Validity range: the fitted span [t_min_c, t_max_c] of the bin means.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "metro/calibration/imu_model.hpp"
#include "metro/core/status.hpp"
#include "metro/io/session.hpp"

namespace metro {

struct ThermalFitOptions {
  double bin_width_c = 0.5;
  int min_samples_per_bin = 10;  // Bins with fewer are left out.
  int max_order = 4;
  int order = 0;        // 0: chosen by the data; 1..max_order: fixed.
  double alpha = 0.05;  // Family level of the nested F-tests (each at alpha / (max - 1)).
  // The span an order needs: span_per_order_c * order (5 degC for order 1, issue #42).
  double span_per_order_c = 5.0;
  // A read error: |temp_c - median of the glitch_window samples each side| > glitch_c.
  double glitch_c = 2.0;
  int glitch_window = 5;
  bool separate_legs = true;  // Fit the hysteresis when heating and cooling legs both exist.
  double min_leg_span_c = 5.0;

  bool IsValid(std::string* why) const;
};

// One step of the order choice: order `order` against order - 1.
struct OrderTest {
  int order = 0;
  double f = 0;        // F statistic (1, dof).
  double dof = 0;      // Residual degrees of freedom of the larger model.
  double p_value = 1;  // Upper tail of F(1, dof) at f.
};

struct ThermalAxisFit {
  int order = 0;
  Eigen::VectorXd coefficients;  // c_0 .. c_order [unit/degC^j]
  Eigen::VectorXd u;             // Standard uncertainties, sqrt(diag(covariance)).
  Eigen::MatrixXd covariance;    // [c_0..c_order, h] when has_hysteresis.
  bool has_hysteresis = false;
  double hysteresis = 0;  // h = heating minus cooling [unit]
  double u_hysteresis = 0;
  double residual_rms = 0;  // Of the bin means [unit].
  double dof = 0;
  std::vector<OrderTest> tests;

  // b(T) on the mean of the legs (leg = 0) and its standard uncertainty from the covariance
  // (JCGM 100:2008 5.2.2, sensitivity (1, x, .., x^p)).
  double BiasAt(double temp_c, double t_ref_c) const;
  double UBiasAt(double temp_c, double t_ref_c) const;
};

struct ThermalFit {
  double t_ref_c = 0;
  double t_min_c = 0;  // Validity range: the span of the bin means.
  double t_max_c = 0;
  int bins = 0;
  bool legs = false;                    // Heating and cooling legs fitted with a hysteresis term.
  std::vector<int64_t> excluded_lines;  // Temperature read errors left out.
  std::array<ThermalAxisFit, 3> axes;
};

// The input: per sample temperature, the three axes' values and each sample's source line
// (for the messages). `what` names the record and sensor in messages ("s.csv sensor 2 gyro").
struct ThermalSamples {
  std::string what;
  std::vector<double> temp_c;
  std::array<std::vector<double>, 3> values;
  std::vector<int64_t> lines;
};

// Fits the three axes. t_ref_c: the reference; NaN = the middle of the fitted span.
// Errors: options invalid, a span too small for the order (the span it has and the one needed).
Result<ThermalFit> FitThermalBias(const ThermalSamples& samples, const ThermalFitOptions& options,
                                  double t_ref_c);

// The raw LSB columns of `sensor` (InputColumns(sensor, "LSB")) and temp_c of `tag`; an error
// names the missing column ("s.csv: sensor 2 gyro: no temp_c column: a thermal fit needs the
// die temperature per sample") and the columns the tag has.
// The record is one static pose. For the accelerometer the gravity reading is removed: on the
// axis whose mean reading is largest, +-32768 / accel_fs_g LSB (the nominal 1 g, imu_model.hpp
// NominalScale); that mean must lie within 15 % of it (else an error: not one pose on a face).
// So that axis's c_0 holds its scale error at 1 g and its c_1.. the scale's temperature terms
// times 1 g; the other axes' c_0 hold any tilt of the pose (docs/thermal.md).
Result<ThermalSamples> ThermalSamplesFromTag(const Tag& tag, ImuSensor sensor,
                                             const std::string& path, double accel_fs_g = 2.0);

// Both sensors of one tag from one record (`calibrate fit --thermal`).
struct ThermalTagFit {
  int sensor = 0;
  std::string path;
  ThermalFit accel;  // [LSB], [LSB/degC^j]
  ThermalFit gyro;
};
Result<ThermalTagFit> FitThermalTag(const Tag& tag, const std::string& path,
                                    const ThermalFitOptions& options);

// The fits as JSON ("metro.thermal-fit/1", docs/thermal.md "Output"): per tag and sensor the
// reference, validity range, bins, excluded lines and, per axis, the order with its F-tests,
// c_0..c_p under calibration.json's names (bias, bias_per_c, bias_per_c2, bias_per_c3,
// bias_per_c4) with u, the covariance, the residual RMS and the hysteresis when fitted.
std::string ThermalFitJson(const std::vector<ThermalTagFit>& fits, const ThermalFitOptions& o);

// Indices of temperature read errors (ThermalFitOptions::glitch_c, glitch_window).
std::vector<size_t> FindTemperatureGlitches(const std::vector<double>& temp_c, double glitch_c,
                                            int window);

}  // namespace metro
