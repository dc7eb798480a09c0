#include <catch2/catch.hpp>
#include <string>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

TEST_CASE("imu_tk two-file format loads as raw counts", "[io][imutk]") {
  TempFile acc("2.984e-02 3.2768e+04 3.2700e+04 3.6000e+04\n4.0e-02  32769 32701 36001\n", ".mat");
  TempFile gyro("2.984e-02 3.2500e+04 3.2600e+04 3.2700e+04\n4.0e-02\t32501 32601 32701\n", ".mat");
  auto r = LoadImuTk(acc.path(), gyro.path());
  REQUIRE(r.ok());
  const Tag& t = r.value().tags.at(0);
  REQUIRE(t.size() == 2);
  CHECK(t.t_s[0] == 0.02984);
  CHECK(t.Find("az_lsb")->values[1] == 36001);
  CHECK(t.Find("gx_lsb")->values[0] == 32500);
  CHECK(t.Find("gz_lsb")->unit == "LSB");
}

TEST_CASE("imu_tk files with different timestamps are refused", "[io][imutk]") {
  TempFile acc("0.01 1 2 3\n0.02 1 2 3\n", ".mat");
  TempFile gyro("0.01 1 2 3\n0.03 1 2 3\n", ".mat");
  auto r = LoadImuTk(acc.path(), gyro.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().line == 2);
  CHECK(r.error().message.find("differs from the accelerometer's 0.02") != std::string::npos);
  TempFile short_gyro("0.01 1 2 3\n", ".mat");
  auto r2 = LoadImuTk(acc.path(), short_gyro.path());
  REQUIRE_FALSE(r2.ok());
  CHECK(r2.error().message.find("2 samples in") == 0);
  TempFile bad("0.01 1 2\n", ".mat");
  auto r3 = LoadImuTk(bad.path(), gyro.path());
  REQUIRE_FALSE(r3.ok());
  CHECK(r3.error().ToString() == bad.path() + ":1: expected 4 numbers 't x y z', found 3");
}

TEST_CASE("imu_tk Xsens record from the public data set loads", "[io][imutk]") {
  const std::string dir = std::string(METRO_EXTERNAL_DATA_DIR) + "/imu_tk_xsens/";
  auto r = LoadImuTk(dir + "xsens_acc.mat", dir + "xsens_gyro.mat");
  REQUIRE(r.ok());
  const Tag& t = r.value().tags.at(0);
  // SOURCE.md: 51,175 lines, 0.02984 s to 511.718 s, identical timestamps.
  CHECK(t.size() == 51175);
  CHECK(t.t_s.front() == Approx(0.02984));
  CHECK(t.t_s.back() == Approx(511.718).margin(1e-3));
  CHECK(r.value().sha256 ==
        "335a234736ff4dd8741118283d5d4cd389ac54b04d00e6cd8d48ca3e532b7510+"
        "e0d6cc7ccbc996aba3dae5063e97360a8b765ad1dffd02eae8ec69820eb37c1d");
}

}  // namespace
}  // namespace metro
