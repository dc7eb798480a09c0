// imu_tk's public Xsens record (datasets/external/imu_tk_xsens/, SOURCE.md):
// unsigned 16-bit counts around 32768, no temperature, 100 Hz, an initial 50 s static period
// and about 37 hand-placed poses. imu_tk's published result on it: 38 static intervals, an
// accelerometer gravity-norm residual of about 0.008 m/s^2 RMS per static sample (one
// averaged sample per interval), the gyroscope bias frozen at the initial static mean.
#include <catch2/catch.hpp>
#include <cmath>

#include "metro/calibration/calibrate.hpp"
#include "metro/io/session_io.hpp"

namespace metro {
namespace {

TEST_CASE("imu_tk Xsens record calibrates at least as well as imu_tk", "[calibration][slow]") {
  const std::string dir = std::string(METRO_EXTERNAL_DATA_DIR) + "/imu_tk_xsens/";
  Result<Session> session = LoadImuTk(dir + "xsens_acc.mat", dir + "xsens_gyro.mat");
  REQUIRE(session.ok());
  CalibrationOptions o;
  o.gravity_mps2 = 9.81744;  // The g imu_tk's test program uses for this record.
  // No full-scale setting applies to these counts: the start is the ellipsoid fit.
  Result<Calibration> cal = CalibrateSessions({&session.value()}, o);
  if (!cal.ok()) FAIL(cal.error().ToString());
  REQUIRE(cal.value().tags.size() == 1);
  const TagCalibration& t = cal.value().tags.front();
  REQUIRE(t.accel.has_value());
  REQUIRE(t.gyro.has_value());
  // At least imu_tk's 38 static intervals.
  CHECK(t.accel->segments.size() >= 38);
  // The gravity-norm residual per static interval, in m/s^2, no worse than imu_tk's 0.008.
  const double rms_mps2 = t.accel->residual_rms * kStandardGravityMps2;
  INFO("accel residual " << rms_mps2 << " m/s^2 over " << t.accel->segments.size() << " poses");
  CHECK(rms_mps2 <= 0.008);
  // Over every raw static sample the residual is the sensor noise (about 0.008 m/s^2 on this
  // record, the figure imu_tk's per-sample number matches); it must not exceed it by more than
  // rounding of the published figure.
  REQUIRE(t.accel->groups.size() >= 2);
  CHECK(t.accel->groups[1].kind == "static_sample_norm");
  CHECK(t.accel->groups[1].rms * kStandardGravityMps2 <= 0.0085);
  // SOURCE.md: imu_tk's own calibration has 412..415 counts per m/s^2 and 4764..4778 counts
  // per rad/s; the sensitivities found here agree within 1 %.
  for (int a = 0; a < 3; ++a) {
    const double counts_per_mps2 = t.accel->sensitivity[a] / kStandardGravityMps2;
    CHECK(counts_per_mps2 > 408.0);
    CHECK(counts_per_mps2 < 419.0);
    const double counts_per_rads = t.gyro->sensitivity[a] * 180.0 / 3.14159265358979323846;
    CHECK(counts_per_rads > 4716.0);
    CHECK(counts_per_rads < 4826.0);
    // Biases near the 32768 offset, estimated with an uncertainty.
    CHECK(std::abs(t.accel->model.bias[a] - 32768.0) < 1500.0);
    CHECK(std::abs(t.gyro->model.bias[a] - 32768.0) < 1500.0);
    CHECK(t.gyro->bias_u[a] > 0.0);
  }
  // The gyroscope bias is estimated (not frozen): free in the fit, with its covariance.
  CHECK(t.gyro->parameter_names.front() == "b_x");
  CHECK(t.gyro->residual_unit == "deg");
  CHECK(t.gyro->residual_rms < 2.0);
}

}  // namespace
}  // namespace metro
