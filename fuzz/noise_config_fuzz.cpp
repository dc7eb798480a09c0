// libFuzzer target: `characterize noise-compare FILE REPORT.json`'s reader of estimators' noise
// files (noise/noise_config_reader.hpp: flat and OpenCV YAML, one nesting level, flow lists,
// PX4 `param set`, basalt JSON), then the format detection and the key checks and comparison
// against a fixed record; a document starting with '{' also goes to the spec library reader
// (noise/spec_library.hpp, --spec-library). No file is written: both readers take text.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "metro/noise/noise_config_reader.hpp"
#include "metro/noise/spec_library.hpp"

namespace {

// Three accelerometer and three gyroscope axes with N and K resolved (EuRoC's magnitudes), so
// a file that passes the key checks reaches the comparison.
const metro::NoiseExportInput& Record() {
  static const metro::NoiseExportInput in = [] {
    metro::NoiseExportInput r;
    r.source = "fuzz";
    for (char axis : {'x', 'y', 'z'}) {
      for (auto [name, unit, n, k] :
           {std::tuple{"a", "m/s^2", 2e-3, 3e-3}, std::tuple{"g", "rad/s", 1.7e-4, 2e-5}}) {
        metro::NoiseExportAxis a;
        a.quantity = std::string(name) + axis + (unit[0] == 'm' ? "_mps2" : "_rads");
        a.unit = unit;
        a.allan.sample_period.rate_hz = 200.0;
        for (auto [t, v] : {std::pair{metro::NoiseTerm::kRandomWalk, n},
                            std::pair{metro::NoiseTerm::kRateRandomWalk, k}}) {
          metro::AllanNoiseTermReport& term = a.allan.noise[static_cast<size_t>(t)];
          term.value = v;
          term.u = 0.01 * v;
          term.supported = true;
        }
        r.axes.push_back(a);
      }
    }
    return r;
  }();
  return in;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  metro::Result<metro::NoiseConfigFile> config = metro::ReadNoiseConfig(text, "imu.yaml");
  if (config.ok()) {
    metro::Result<metro::NoiseExportFormat> format = metro::DetectNoiseConfigFormat(config.value());
    if (format.ok()) {
      metro::NoiseExportOptions options;
      options.format = format.value();
      metro::Result<metro::NoiseComparison> c =
          metro::CompareNoiseConfig(config.value(), Record(), options);
      if (c.ok()) (void)metro::NoiseComparisonTable(c.value());
    }
  }
  if (size > 0 && data[0] == '{') {
    metro::Result<metro::SpecLibrary> lib = metro::ParseSpecLibrary(text, "specs.json");
    if (lib.ok() && !lib.value().parts.empty()) {
      (void)metro::SpecSourcesTable(lib.value().parts.front(), "");
    }
  }
  return 0;
}
