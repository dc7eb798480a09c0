// Constants marked model_rejected (issue #36) through the programs: a page is a view, not a use
// (`characterize report` renders it under a banner, exit 0; `calibrate report` prints it first),
// while the certificate, `calibrate blob` and push refuse them without --accept-rejected-model.
#include <catch2/catch.hpp>
#include <string>

#include "metro/core/file.hpp"
#include "support/bundled_fit.hpp"
#include "support/run_program.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using Run = testing::ProgramRun;

const std::string kDatasets = std::string(METRO_SOURCE_DIR) + "/datasets/";

const std::string& Scratch() {
  static const testing::ScratchFolder folder("metro_model_rejected_cli");
  return folder.path();
}

Run Calibrate(const std::string& args) { return testing::RunProgram(METRO_CALIBRATE_EXE, args); }
Run Characterize(const std::string& args) {
  return testing::RunProgram(METRO_CHARACTERIZE_EXE, args);
}

std::string Slurp(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  REQUIRE(text.ok());
  return text.value();
}

// The bundled session under --model bias: both sensors' bias models are rejected (the data need
// the scale factors), so both are marked model_rejected.
// Fitted once per build for all the test processes (support/bundled_fit.hpp).
const std::string& RejectedCalibration() {
  static const std::string path = testing::BundledFit("--model bias");
  return path;
}

TEST_CASE("characterize report renders model_rejected constants under a banner (exit 0)",
          "[calibration][report][cli]") {
  const std::string page = Scratch() + "view.html";
  const Run r = Characterize("report " + RejectedCalibration() + " --html " + page);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("warning: " + RejectedCalibration() +
                                    ": sensor 2 accel: the data reject the accelerometer 'bias'"));
  CHECK_THAT(r.err, Catch::Contains("the page is a view, not a certificate"));
  const std::string html = Slurp(page);
  CHECK_THAT(html, Catch::Contains("<title>Calibration report (not a certificate)</title>"));
  CHECK_THAT(html, Catch::Contains("Not a certificate: constants marked model_rejected"));
  CHECK_THAT(html, Catch::Contains("<b>sensor 2 accelerometer</b> (&apos;bias&apos; model, "
                                   "rejected): the data reject the accelerometer"));
  CHECK_THAT(html, Catch::Contains("<b>sensor 2 gyroscope</b>"));
  CHECK_THAT(html, Catch::Contains("Not certified (marked model_rejected"));
  CHECK(html.find("Calibration certificate") == std::string::npos);
}

TEST_CASE("calibrate report prints model_rejected first; its certificate is refused",
          "[calibration][report][cli]") {
  Run r = Calibrate("report " + RejectedCalibration());
  CHECK(r.exit_code == 0);
  const size_t banner = r.out.find("MODEL_REJECTED: these constants are not certified");
  CHECK(banner != std::string::npos);
  CHECK(banner < r.out.find("sensor 2: static detector factor"));
  CHECK_THAT(r.out, Catch::Contains("\n  sensor 2 gyro: the data reject the gyroscope 'bias'"));
  // The certificate refuses them (exit 2, nothing written) and says how to view the file.
  const std::string cert = Scratch() + "cert.html";
  r = Calibrate("report " + RejectedCalibration() + " --html " + cert);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err,
             Catch::Contains("characterize report " + RejectedCalibration() + " --html PAGE.html"));
  CHECK_FALSE(ReadFile(cert).ok());
  r = Calibrate("report " + RejectedCalibration() + " --html " + cert + " --accept-rejected-model");
  CHECK(r.exit_code == 0);
  CHECK_THAT(Slurp(cert), Catch::Contains("<title>Calibration certificate</title>"));
}

TEST_CASE("calibrate blob refuses model_rejected constants unless accepted",
          "[calibration][blob][cli]") {
  const std::string blob = Scratch() + "tag.bin";
  Run r = Calibrate("blob " + RejectedCalibration() +
                    " --sensor 2 --device-id 9ABCDEF012345678 -o " + blob);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("model_rejected"));
  CHECK_FALSE(ReadFile(blob).ok());
  r = Calibrate("blob " + RejectedCalibration() +
                " --sensor 2 --device-id 9ABCDEF012345678 --accept-rejected-model -o " + blob);
  INFO(r.err);
  CHECK(r.exit_code == 0);
  CHECK(ReadFile(blob).ok());
}

}  // namespace
}  // namespace metro
