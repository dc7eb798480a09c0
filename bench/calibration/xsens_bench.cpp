// End-to-end calibration of imu_tk's Xsens record: load the two text files, segment, fit the
// accelerometer and gyroscope, compute the covariances and render calibration.json.
//
//   metro_bench_calibration_xsens [REPEATS] [DATASET_DIR] [auto|one]
//
// Prints per-stage wall times (median and minimum over REPEATS, default 7) and the fit
// figures that the comparison with imu_tk needs (static intervals, residuals). `auto` (the
// default) fits as `calibrate fit` does since issue #36: the model ladder bias < scale < full
// of both sensors, compared and chosen (--model auto); `one`: the library's default, the full
// models alone without comparison (what `calibrate fit` did before issue #36).
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

#include "metro/calibration/calibration_io.hpp"
#include "metro/io/session_io.hpp"

namespace {

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
  const std::string dir =
      argc > 2 ? argv[2] : std::string(METRO_EXTERNAL_DATA_DIR) + "/imu_tk_xsens";
  const std::string mode = argc > 3 ? argv[3] : "auto";
  if (mode != "auto" && mode != "one") {
    fmt::print(stderr, "error: the third argument is auto or one, not {}\n", mode);
    return 2;
  }
  metro::CalibrationOptions options;
  options.gravity_mps2 = 9.81744;  // As imu_tk's test program for this record.
  options.accel_auto = options.gyro_auto = options.compare_models = mode == "auto";
  std::vector<double> load_s, fit_s, json_s, total_s;
  metro::Calibration last;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    metro::Result<metro::Session> session =
        metro::LoadImuTk(dir + "/xsens_acc.mat", dir + "/xsens_gyro.mat");
    if (!session.ok()) {
      fmt::print(stderr, "error: {}\n", session.error().ToString());
      return 2;
    }
    const auto t1 = std::chrono::steady_clock::now();
    metro::Result<metro::Calibration> cal = metro::CalibrateSessions({&session.value()}, options);
    if (!cal.ok()) {
      fmt::print(stderr, "error: {}\n", cal.error().ToString());
      return 1;
    }
    const auto t2 = std::chrono::steady_clock::now();
    const std::string json = metro::FormatCalibrationJson(cal.value());
    const auto t3 = std::chrono::steady_clock::now();
    load_s.push_back(Seconds(t0, t1));
    fit_s.push_back(Seconds(t1, t2));
    json_s.push_back(Seconds(t2, t3));
    total_s.push_back(Seconds(t0, t3));
    last = std::move(cal).value();
  }
  const metro::TagCalibration& t = last.tags.front();
  fmt::print("imu_tk Xsens record, {} repeats (median / min wall time), models: {}\n", repeats,
             mode == "auto" ? "auto (the ladder, as calibrate fit)" : "full only");
  fmt::print("  load both files     {:.3f} / {:.3f} s\n", Median(load_s),
             *std::min_element(load_s.begin(), load_s.end()));
  fmt::print("  calibrate           {:.3f} / {:.3f} s\n", Median(fit_s),
             *std::min_element(fit_s.begin(), fit_s.end()));
  fmt::print("  calibration.json    {:.3f} / {:.3f} s\n", Median(json_s),
             *std::min_element(json_s.begin(), json_s.end()));
  fmt::print("  end to end          {:.3f} / {:.3f} s   (imu_tk published: ~0.8 s)\n",
             Median(total_s), *std::min_element(total_s.begin(), total_s.end()));
  int counts[3] = {0, 0, 0};
  for (const metro::Segment& s : t.segments) ++counts[static_cast<int>(s.kind)];
  fmt::print("  segments: {} static, {} rotation (threshold factor {})\n", counts[0], counts[2],
             t.threshold_factor);
  for (const metro::ResidualGroup& g : t.accel->groups) {
    fmt::print("  accel {:<18} n {:<6} rms {:.4g} {} = {:.4g} m/s^2\n", g.kind, g.count, g.rms,
               g.unit, g.rms * metro::kStandardGravityMps2);
  }
  for (const metro::ResidualGroup& g : t.gyro->groups) {
    fmt::print("  gyro  {:<18} n {:<6} rms {:.4g} {}\n", g.kind, g.count, g.rms, g.unit);
  }
  fmt::print("  accel reduced chi^2 {:.3f}, gyro reduced chi^2 {:.3f}, iterations {}\n",
             t.accel->reduced_chi2, t.gyro->reduced_chi2, t.iterations);
  return 0;
}
