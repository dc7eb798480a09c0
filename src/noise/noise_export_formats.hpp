// The key tables and writers of the noise export formats (noise/noise_export.hpp), shared by
// the exporter and the reader of noise-compare (noise_config_reader.hpp). Private to the
// library.
#pragma once

#include <string>
#include <vector>

#include "metro/io/columns.hpp"
#include "metro/noise/noise_export.hpp"
#include "metro/noise/noise_model.hpp"

namespace metro {

// How a file's value follows from the continuous SI term v (N or K):
enum class ExportValueKind {
  kContinuous,      // v itself (Kalibr's continuous-time values).
  kPx4PerStep,      // v * sqrt(f_predict): PX4 EKF2's per-step parameters (N and K alike).
  kSampleVariance,  // v^2 * f_record: a message's per-sample variance (white noise only).
};

struct ExportKeySpec {
  std::string key;  // As the reader flattens it (see ExportedNoiseValue::key).
  SensorKind sensor = SensorKind::kNone;
  NoiseTerm term = NoiseTerm::kRandomWalk;
  ExportValueKind kind = ExportValueKind::kContinuous;
};

// The keys of one instrument's term: one key (a scalar, reduced over the axes) or three
// (per_axis: x, y, z).
struct ExportKeyGroup {
  SensorKind sensor = SensorKind::kNone;
  NoiseTerm term = NoiseTerm::kRandomWalk;
  bool per_axis = false;
  std::vector<ExportKeySpec> keys;
};

// Keys a file holds besides the noise values.
enum class ExportMetaKind {
  kRate,   // The update rate [Hz]: written as the record's rate, read as a positive number.
  kTopic,  // A ROS topic: any text.
  kZero,   // An off-diagonal covariance element: written and read as 0.
};
struct ExportMetaKey {
  std::string key;
  ExportMetaKind kind = ExportMetaKind::kRate;
};

std::vector<ExportKeyGroup> ExportKeyGroups(NoiseExportFormat format);
std::vector<ExportMetaKey> ExportMetaKeys(NoiseExportFormat format);

// "N" (random_walk), "K" (rate_random_walk), and the other IEEE 952 symbols.
const char* NoiseTermSymbol(NoiseTerm term);

// The unit of a key's value, e.g. "rad/s/sqrt(Hz)", "m/s^3", "(rad/s)^2".
std::string ExportUnit(const ExportKeySpec& spec);
// The convention of a key's value in a phrase.
std::string ExportConvention(const ExportKeySpec& spec, double px4_rate_hz);

// The whole file: the convention block and the values.
std::string ExportText(const NoiseExport& values, const std::string& source,
                       const NoiseExportOptions& options);

}  // namespace metro
