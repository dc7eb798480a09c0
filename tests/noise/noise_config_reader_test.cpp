// Reading noise files back (issue #40 step 3): every class of bad input at its
// file:line:column, counted independently of the reader (support/text_position.hpp).
#include "metro/noise/noise_config_reader.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <random>
#include <string>

#include "support/text_position.hpp"

namespace metro {
namespace {

NoiseExportAxis Axis(const std::string& quantity, const std::string& unit, double n, double k) {
  NoiseExportAxis a;
  a.quantity = quantity;
  a.unit = unit;
  a.allan.sample_period.rate_hz = 200.0;
  for (auto [t, v] : {std::pair{NoiseTerm::kRandomWalk, n}, {NoiseTerm::kRateRandomWalk, k}}) {
    AllanNoiseTermReport& r = a.allan.noise[static_cast<size_t>(t)];
    r.value = v;
    r.u = 0.01 * v;
    r.supported = true;
  }
  return a;
}

NoiseExportInput Record() {
  NoiseExportInput in;
  in.source = "test";
  for (char axis : {'x', 'y', 'z'}) {
    in.axes.push_back(Axis(std::string("a") + axis + "_mps2", "m/s^2", 2e-3, 3e-3));
    in.axes.push_back(Axis(std::string("g") + axis + "_rads", "rad/s", 1.7e-4, 2e-5));
  }
  return in;
}

// Kalibr's own example values (EuRoC, kalibr wiki "yaml formats").
const std::string kKalibr =
    "rostopic: /imu0\n"
    "update_rate: 200.0 #Hz\n"
    "\n"
    "accelerometer_noise_density: 2.0000e-3 # [ m / s^2 / sqrt(Hz) ]\n"
    "accelerometer_random_walk: 3.0000e-3   # [ m / s^3 / sqrt(Hz) ]\n"
    "gyroscope_noise_density: 1.6968e-04    # [ rad / s / sqrt(Hz) ]\n"
    "gyroscope_random_walk: 1.9393e-05      # [ rad / s^2 / sqrt(Hz) ]\n";

// The error of comparing `text` as the options' format with Record().
Error CompareError(const std::string& text, NoiseExportFormat format) {
  const Result<NoiseConfigFile> read = ReadNoiseConfig(text, "f.yaml");
  if (!read.ok()) return read.error();
  NoiseExportOptions o;
  o.format = format;
  const Result<NoiseComparison> c = CompareNoiseConfig(read.value(), Record(), o);
  REQUIRE_FALSE(c.ok());
  return c.error();
}

std::string Where(const Error& e) {
  return std::to_string(e.line) + ":" + std::to_string(e.column);
}

TEST_CASE("Kalibr's example imu.yaml reads and compares", "[export]") {
  const Result<NoiseConfigFile> read = ReadNoiseConfig(kKalibr, "imu.yaml");
  REQUIRE(read.ok());
  REQUIRE(DetectNoiseConfigFormat(read.value()).ok());
  CHECK(DetectNoiseConfigFormat(read.value()).value() == NoiseExportFormat::kKalibr);
  NoiseExportOptions o;
  const Result<NoiseComparison> c = CompareNoiseConfig(read.value(), Record(), o);
  REQUIRE(c.ok());
  REQUIRE(c.value().rows.size() == 4);
  // accelerometer_noise_density 2.0e-3 against N = 2e-3 m/s^2/sqrt(Hz): ratio 1.
  CHECK(c.value().rows[0].ratio == Approx(1.0));
  // gyroscope_random_walk 1.9393e-05 against K = 2e-5 (u 2e-7): E_n = (x - X) / (2 u).
  CHECK(c.value().rows[3].ratio == Approx(1.9393e-05 / 2e-5));
  CHECK(c.value().rows[3].e_n == Approx((1.9393e-05 - 2e-5) / (2.0 * 2e-7)));
}

TEST_CASE("Bad noise files fail at file:line:column with what was expected", "[export]") {
  SECTION("negative density") {
    std::string text = kKalibr;
    const size_t at = text.find("1.6968e-04");
    text.replace(at, 10, "-1.6968e-04");
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(e.file == "f.yaml");
    CHECK(Where(e) == testing::LineColumn(text, at));
    CHECK(e.message ==
          "gyroscope_noise_density: expected a non-negative noise value (a standard deviation or "
          "variance), found -1.6968e-04");
  }
  SECTION("unknown key, with the nearest") {
    std::string text = kKalibr;
    const size_t at = text.find("gyroscope_random_walk");
    text.replace(at, 21, "gyroscope_randomwalk");
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == testing::LineColumn(text, at));
    CHECK(e.message.find("unknown key 'gyroscope_randomwalk' in a kalibr noise file; expected one "
                         "of rostopic, update_rate, accelerometer_noise_density,") == 0);
    CHECK(e.message.find("(nearest: gyroscope_random_walk)") != std::string::npos);
  }
  SECTION("missing key") {
    std::string text = kKalibr;
    const size_t at = text.find("accelerometer_random_walk");
    text.erase(at, text.find('\n', at) + 1 - at);
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == "1:1");
    CHECK(e.message.find("missing key 'accelerometer_random_walk'; a kalibr noise file holds") ==
          0);
  }
  SECTION("missing key under imu0: at the mapping's first key") {
    const std::string text =
        "%YAML:1.0\nimu0:\n  rostopic: /imu0\n  update_rate: 200\n"
        "  accelerometer_noise_density: 2e-3\n  accelerometer_random_walk: 3e-3\n"
        "  gyroscope_noise_density: 1.7e-4\n";
    const Error e = CompareError(text, NoiseExportFormat::kOpenVins);
    CHECK(Where(e) == testing::LineColumn(text, text.find("rostopic")));
    CHECK(e.message.find("missing key 'imu0.gyroscope_random_walk'") == 0);
  }
  SECTION("not a number") {
    std::string text = kKalibr;
    const size_t at = text.find("3.0000e-3");
    text.replace(at, 9, "3.0e-3x");
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == testing::LineColumn(text, at));
    CHECK(e.message == "accelerometer_random_walk: expected a number, found '3.0e-3x'");
  }
  SECTION("a rate that is not positive") {
    std::string text = kKalibr;
    const size_t at = text.find("200.0");
    text.replace(at, 5, "0");
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == testing::LineColumn(text, at));
    CHECK(e.message == "update_rate: expected a positive rate in Hz, found 0");
  }
  SECTION("a key given twice") {
    const std::string text = kKalibr + "gyroscope_noise_density: 1e-4\n";
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == testing::LineColumn(text, text.rfind("gyroscope_noise_density")));
    CHECK(e.message == "'gyroscope_noise_density' is given twice; expected each key once");
  }
  SECTION("a line that is not key: value") {
    std::string text = kKalibr;
    const size_t at = text.find("\n\n") + 2;
    text.insert(at, "  gyro noise 0.1\n");
    const Error e = CompareError(text, NoiseExportFormat::kKalibr);
    CHECK(Where(e) == testing::LineColumn(text, at + 2));
    CHECK(e.message == "expected `key: value` (YAML), `param set NAME VALUE` (PX4) or a # comment");
  }
  SECTION("PX4 negative bias noise") {
    const std::string text =
        "param set EKF2_GYR_NOISE 0.0017\nparam set EKF2_ACC_NOISE 0.02\n"
        "param set EKF2_GYR_B_NOISE -2e-4\nparam set EKF2_ACC_B_NOISE 3e-2\n";
    const Error e = CompareError(text, NoiseExportFormat::kPx4Ekf2);
    CHECK(Where(e) == testing::LineColumn(text, text.find("-2e-4")));
    CHECK(e.message.find("EKF2_GYR_B_NOISE: expected a non-negative noise value") == 0);
  }
  SECTION("ROS off-diagonal not 0, a list element at its column") {
    const std::string text =
        "angular_velocity_covariance: [1e-6, 0, 0, 0, 1e-6, 0, 0, 0.5, 1e-6]\n"
        "linear_acceleration_covariance: [1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3]\n";
    const Error e = CompareError(text, NoiseExportFormat::kRos);
    CHECK(Where(e) == testing::LineColumn(text, text.find("0.5")));
    CHECK(e.message.find("angular_velocity_covariance[7]: expected 0 (an off-diagonal") == 0);
  }
  SECTION("basalt JSON negative, at its position") {
    const std::string text =
        "{\"value0\": {\"imu_update_rate\": 200,\n"
        " \"accel_noise_std\": [2e-3, 2e-3, 2e-3], \"gyro_noise_std\": [1e-4, 1e-4, 1e-4],\n"
        " \"accel_bias_std\": [3e-3, -3e-3, 3e-3], \"gyro_bias_std\": [2e-5, 2e-5, 2e-5]}}\n";
    const Error e = CompareError(text, NoiseExportFormat::kBasalt);
    CHECK(Where(e) == testing::LineColumn(text, text.find("-3e-3")));
    CHECK(e.message.find("value0.accel_bias_std[1]: expected a non-negative") == 0);
  }
  SECTION("no key of any format") {
    const Result<NoiseConfigFile> read = ReadNoiseConfig("foo: 1\nbar: 2\n", "f.yaml");
    REQUIRE(read.ok());
    const Result<NoiseExportFormat> f = DetectNoiseConfigFormat(read.value());
    REQUIRE_FALSE(f.ok());
    CHECK(f.error().ToString().find("f.yaml:1:1: no key of a known noise file; expected the keys "
                                    "of one of: kalibr (accelerometer_noise_density)") == 0);
  }
}

TEST_CASE("Mutated noise files read, or fail at a line and column inside the file", "[export]") {
  // Random edits of every exported format (characters the grammars care about): no crash, and
  // every error points into the text (line 1..lines, column >= 1).
  const NoiseExportInput in = Record();
  std::mt19937_64 rng(4040);
  const std::string alphabet = ":#[],-+.eE0123456789 \t\n\"'{}abc_x";
  int failures_with_position = 0, accepted = 0;
  for (NoiseExportFormat f : kAllNoiseExportFormats) {
    NoiseExportOptions o;
    o.format = f;
    const Result<NoiseExport> e = ExportNoise(in, o);
    REQUIRE(e.ok());
    for (int trial = 0; trial < 300; ++trial) {
      std::string text = e.value().text;
      const int edits = 1 + static_cast<int>(rng() % 3);
      for (int k = 0; k < edits; ++k) {
        const size_t at = rng() % (text.size() + 1);
        const char c = alphabet[rng() % alphabet.size()];
        switch (rng() % 3) {
          case 0:
            text.insert(at, 1, c);
            break;
          case 1:
            if (at < text.size()) text.erase(at, 1);
            break;
          default:
            if (at < text.size()) text[at] = c;
        }
      }
      const int64_t lines = 1 + std::count(text.begin(), text.end(), '\n');
      Result<NoiseConfigFile> read = ReadNoiseConfig(text, "m");
      Result<NoiseComparison> c = MakeError("not compared");
      if (read.ok()) c = CompareNoiseConfig(read.value(), in, o);
      if (c.ok()) {
        ++accepted;
        for (const NoiseComparisonRow& r : c.value().rows) CHECK(r.file_value >= 0.0);
        continue;
      }
      const Error& err = read.ok() ? c.error() : read.error();
      INFO(NoiseExportFormatName(f) << " trial " << trial << ": " << err.ToString());
      CHECK(err.file == "m");
      CHECK(err.line >= 1);
      CHECK(err.line <= lines);
      CHECK(err.column >= 1);
      ++failures_with_position;
    }
  }
  // Most single edits land in a comment and change nothing; the rest fail at a position.
  CHECK(accepted > 0);
  CHECK(failures_with_position > 0);
}

}  // namespace
}  // namespace metro
