// libFuzzer target: calibration.json ("metro.calibration/1", docs/calibration-format.md), as
// `calibrate apply`, `calibrate report` and `calibrate blob` read it. A file that loads is
// rendered (JSON and the readable report), written and read back (a loaded calibration must
// survive its own round trip), and turned into a blob for each of its tags.
#include <cstddef>
#include <cstdint>

#include "fuzz_input.hpp"
#include "metro/blob/from_calibration.hpp"
#include "metro/calibration/calibration_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& path = metro_fuzz::WriteInput(data, size, "calibration.json");
  metro::Result<metro::Calibration> calibration = metro::LoadCalibration(path);
  if (!calibration.ok()) return 0;
  const metro::Calibration& cal = calibration.value();
  (void)metro::FormatCalibrationReport(cal);
  const std::string text = metro::FormatCalibrationJson(cal);
  (void)metro::CalibrationFromJson(text, path);
  for (const metro::TagCalibration& tag : cal.tags) {
    metro::blob::BlobFromCalibrationOptions options;
    options.sensor = tag.sensor;
    options.device_id = 0x0123456789ABCDEFull;
    auto contents = metro::blob::BlobContentsFromCalibration(cal, options);
    if (contents.ok()) (void)metro::blob::WriteBlob(contents.value());
  }
  return 0;
}
