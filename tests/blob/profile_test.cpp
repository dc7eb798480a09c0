// The nominal sensitivity a blob section declares (--profile mpu6050|generic, --accel-fs-g,
// --gyro-fs-dps; docs/calibration-blob.md section 10 "Nominal sensitivity"), and the refusal of
// constants the format cannot represent, in `calibrate push` before any port is opened.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "metro/blob/from_calibration.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/core/file.hpp"
#include "metro/io/session_io.hpp"
#include "support/run_program.hpp"

namespace metro::blob {
namespace {

const std::string kGolden = std::string(METRO_SOURCE_DIR) + "/datasets/golden/";

Calibration Golden() {
  Result<Calibration> cal = LoadCalibration(kGolden + "calibration_sensor2.json");
  REQUIRE(cal.ok());
  return cal.value();
}

BlobFromCalibrationOptions Options() {
  BlobFromCalibrationOptions o;
  o.sensor = 2;
  o.device_id = 0x9ABCDEF012345678ull;
  o.seq = 3;
  return o;
}

// The golden calibration with its gyroscope's counts per deg/s multiplied by `factor` (M and
// its uncertainty divided by it), as another IMU would have.
Calibration WithGyroSensitivity(double factor) {
  Calibration cal = Golden();
  SensorCalibration& g = *cal.tags.at(0).gyro;
  g.model.scale /= factor;
  g.matrix.reset();
  DeriveUncertainties(&g);
  return cal;
}

Result<std::vector<uint8_t>> Blob(const Calibration& cal, const BlobFromCalibrationOptions& o) {
  Result<BlobContents> c = BlobContentsFromCalibration(cal, o);
  if (!c.ok()) return c.error();
  return WriteBlob(c.value());
}

}  // namespace

TEST_CASE("Declared MPU6050 full-scale settings give the inferred blob byte for byte", "[blob]") {
  // The golden calibration is of an MPU6050 at +-2 g and +-250 deg/s (datasets/golden/SOURCE.md).
  Result<std::vector<uint8_t>> inferred = Blob(Golden(), Options());
  REQUIRE(inferred.ok());
  for (SensorProfile p : {SensorProfile::kMpu6050, SensorProfile::kGeneric}) {
    BlobFromCalibrationOptions o = Options();
    o.profile = p;
    o.accel_fs_g = 2.0;
    o.gyro_fs_dps = 250.0;
    Result<std::vector<uint8_t>> declared = Blob(Golden(), o);
    INFO(SensorProfileName(p));
    REQUIRE(declared.ok());
    CHECK(declared.value() == inferred.value());
  }
  // generic without flags: the nominal from M itself, the same fs_sel here.
  BlobFromCalibrationOptions o = Options();
  o.profile = SensorProfile::kGeneric;
  Result<std::vector<uint8_t>> own = Blob(Golden(), o);
  REQUIRE(own.ok());
  CHECK(own.value() == inferred.value());
}

TEST_CASE("A declared setting the constants do not fit is refused with the figures", "[blob]") {
  BlobFromCalibrationOptions o = Options();
  o.gyro_fs_dps = 500.0;  // 65.5 LSB/(deg/s); the gyroscope has about 131: +100 %.
  Result<BlobContents> c = BlobContentsFromCalibration(Golden(), o);
  REQUIRE_FALSE(c.ok());
  INFO(c.error().message);
  CHECK(c.error().message.find("sensor 2 gyro: the gyro sensitivity 1") == 0);
  CHECK(c.error().message.find("from the nominal 65.54 LSB/(deg/s) of fs_sel 1 (nominal from "
                               "--gyro-fs-dps 500, profile mpu6050)") != std::string::npos);
  CHECK(c.error().message.find("the blob format v1 cannot represent it") != std::string::npos);
  // A full scale the MPU6050 does not have is an option error.
  o.gyro_fs_dps = 300.0;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why ==
        "gyro_fs_dps 300 is not an MPU6050 full-scale setting (250, 500, 1000 or 2000 "
        "deg/s); another IMU's full scale takes profile generic");
  o.profile = SensorProfile::kGeneric;
  CHECK(o.IsValid(&why));
}

TEST_CASE("generic: another IMU's sensitivity within 10 % of a setting becomes a blob", "[blob]") {
  // 140.2 counts per deg/s: +7 % from 131.07 (fs_sel 0), inside the format's +-10 %.
  const Calibration cal = WithGyroSensitivity(1.07);
  BlobFromCalibrationOptions o = Options();
  o.gyro_fs_dps = 32768.0 / 140.2;  // 233.7 deg/s: not an MPU6050 setting
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  o.profile = SensorProfile::kGeneric;
  Result<BlobContents> c = BlobContentsFromCalibration(cal, o);
  REQUIRE(c.ok());
  CHECK(c.value().gyro->fs_sel == 0);
  REQUIRE(WriteBlob(c.value()).ok());
}

TEST_CASE("generic: a sensitivity between two settings is refused naming the ranges", "[blob]") {
  // imu_tk's Xsens gyroscope: 83.2 counts per deg/s (datasets/external/imu_tk_xsens). The
  // nearest setting is fs_sel 1 at 32768 / 500 = 65.536; 83.2 / 65.536 = 1.2695: +27.0 %.
  const double factor = 83.2 / (1.0 / Golden().tags.at(0).gyro->M().rowwise().norm().mean());
  const Calibration cal = WithGyroSensitivity(factor);
  BlobFromCalibrationOptions o = Options();
  o.profile = SensorProfile::kGeneric;
  Result<BlobContents> c = BlobContentsFromCalibration(cal, o);
  REQUIRE_FALSE(c.ok());
  INFO(c.error().message);
  CHECK(c.error().message.find("the gyro sensitivity 83.2 LSB/(deg/s) is +27.0 % from the "
                               "nominal 65.54 LSB/(deg/s) of fs_sel 1") != std::string::npos);
  // 131.072 / 1.1 .. 131.072 / 0.9, and halved per setting.
  CHECK(c.error().message.find("119.2 .. 145.6, 59.58 .. 72.82, 29.79 .. 36.41, 14.89 .. 18.2 "
                               "LSB/(deg/s)") != std::string::npos);
}

TEST_CASE("imu_tk's Xsens calibration: refused naming what format v1 cannot hold", "[blob]") {
  const std::string dir = std::string(METRO_EXTERNAL_DATA_DIR) + "/imu_tk_xsens/";
  Result<Session> session = LoadImuTk(dir + "xsens_acc.mat", dir + "xsens_gyro.mat");
  REQUIRE(session.ok());
  CalibrationOptions co;
  co.gravity_mps2 = 9.81744;  // imu_tk's test program's g for this record
  Result<Calibration> cal = CalibrateSessions({&session.value()}, co);
  REQUIRE(cal.ok());
  BlobFromCalibrationOptions o = Options();
  o.sensor = 1;
  for (SensorProfile p : {SensorProfile::kMpu6050, SensorProfile::kGeneric}) {
    o.profile = p;
    Result<BlobContents> c = BlobContentsFromCalibration(cal.value(), o);
    INFO(SensorProfileName(p));
    REQUIRE_FALSE(c.ok());
    CHECK(c.error().message.find("sensor 1 gyro: the gyro sensitivity 83.") == 0);
  }
  // SOURCE.md: imu_tk's own calibration has 4764 .. 4778 counts per rad/s, i.e. 83.15 .. 83.39
  // per deg/s, 26.9 .. 27.2 % above fs_sel 1's 65.536: between two settings, beyond +-10 %.
  Result<BlobContents> c = BlobContentsFromCalibration(cal.value(), o);
  INFO(c.error().message);
  CHECK((c.error().message.find("is +27.0 % from the nominal 65.54 LSB/(deg/s) of fs_sel 1") !=
             std::string::npos ||
         c.error().message.find("is +26.9 % from the nominal 65.54 LSB/(deg/s) of fs_sel 1") !=
             std::string::npos ||
         c.error().message.find("is +27.1 % from the nominal 65.54 LSB/(deg/s) of fs_sel 1") !=
             std::string::npos));
  CHECK(c.error().message.find("the blob format v1 cannot represent it") != std::string::npos);
}

#ifdef METRO_CALIBRATE_EXE
TEST_CASE("calibrate blob and push --profile; push refuses before opening the port",
          "[blob][apps]") {
  const std::string cal_path = "metro_profile_xsens_like.json";
  REQUIRE(WriteFileAtomically(cal_path,
                              FormatCalibrationJson(WithGyroSensitivity(83.2 * 250.0 / 32768.0)))
              .ok());
  auto run = [](const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); };
  const std::string port = "/nonexistent/metro-tty";
  testing::ProgramRun r =
      run("push --port " + port + " " + cal_path + " --sensor 2 --any-device --profile generic");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("cannot represent it") != std::string::npos);
  CHECK(r.err.find("(nothing sent; " + port + " not opened)") != std::string::npos);
  // A representable calibration gets as far as the port (which does not exist): exit 1.
  r = run("push --port " + port + " " + kGolden + "calibration_sensor2.json --sensor 2 " +
          "--any-device --profile generic --accel-fs-g 2 --gyro-fs-dps 250");
  CHECK(r.exit_code == 1);
  CHECK(r.err.find(port) != std::string::npos);
  CHECK(r.err.find("not opened") == std::string::npos);
  // blob: the same refusal, exit 2, nothing written; a bad setting for the profile is exit 2.
  r = run("blob " + cal_path + " --sensor 2 --device-id 9ABCDEF012345678 --profile generic -o " +
          "metro_profile.bin");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("cannot represent it") != std::string::npos);
  CHECK_FALSE(std::ifstream("metro_profile.bin").good());
  r = run("blob " + kGolden +
          "calibration_sensor2.json --sensor 2 --device-id "
          "9ABCDEF012345678 --gyro-fs-dps 300 -o metro_profile.bin");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("gyro_fs_dps 300 is not an MPU6050 full-scale setting") != std::string::npos);
  r = run("blob " + kGolden +
          "calibration_sensor2.json --sensor 2 --device-id "
          "9ABCDEF012345678 --seq 3 --accel-fs-g 2 --gyro-fs-dps 250 -o metro_profile.bin -q");
  CHECK(r.exit_code == 0);
  Result<std::string> bytes = ReadFile("metro_profile.bin");
  Result<std::string> golden = ReadFile(kGolden + "tag_sensor2.bin");
  REQUIRE(bytes.ok());
  CHECK(bytes.value() == golden.value());
  std::remove("metro_profile.bin");
  std::remove(cal_path.c_str());
}
#endif

}  // namespace metro::blob
