// A sourced library of published IMU noise figures (datasheets and the noise files others
// publish for a part), read from datasets/specs/specs.json (issue #40 step 5; docs/specs.md).
//
// Every figure is traceable: the part, the document (title, number, revision, date), the
// page and table, the value exactly as printed with its unit, its kind and its convention.
// The conventions and how each maps on metro's IEEE Std 952-1997 terms (noise_model.hpp):
//
//   convention               term  what the figure is                      SI unit
//   one_sided_density        N     a datasheet's "noise spectral density" d, rad/s/sqrt(Hz),
//                                  one-sided: N = d / sqrt(2)              m/s^2/sqrt(Hz)
//   random_walk_coefficient  N     N itself (ARW/VRW; Kalibr's *_noise_density, the
//                                  continuous white sigma, two-sided PSD N^2)
//   allan_minimum            B     "in-run bias stability": the minimum of  rad/s, m/s^2
//                                  the Allan deviation (not B = min/0.664)
//   bias_random_walk_coefficient K K (Kalibr's *_random_walk)               rad/s^2/sqrt(Hz),
//                                                                           m/s^3/sqrt(Hz)
//
// Kinds: "min" and "max" are specification limits (a JCGM 106 conformity decision can use
// them); "typ" is a typical value and "unstated" a figure printed without a kind (both give a
// ratio and E_n, never a pass or fail); "config" is a value someone chose for an estimator's
// file (EuRoC's sensor.yaml, Kalibr's sample imu.yaml), not a property of the part.
//
// Units a figure may be printed in, with their exact SI factors (standard gravity
// g0 = 9.80665 m/s^2, CGPM 1901; deg = pi/180 rad; h = 3600 s):
//   deg/s/sqrt(Hz) pi/180   mdps/sqrt(Hz) pi/180e3  rad/s/sqrt(Hz) 1
//   ug/sqrt(Hz) 1e-6 g0     mg/sqrt(Hz) 1e-3 g0     m/s^2/sqrt(Hz) 1
//   deg/sqrt(h) pi/180/60   m/s/sqrt(h) 1/60
//   deg/h pi/180/3600       deg/s pi/180            rad/s 1
//   ug 1e-6 g0              mg 1e-3 g0              m/s^2 1
//   rad/s^2/sqrt(Hz) 1      m/s^3/sqrt(Hz) 1
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "metro/core/status.hpp"
#include "metro/io/columns.hpp"
#include "metro/noise/noise_model.hpp"

namespace metro {

enum class SpecConvention {
  kOneSidedDensity,
  kRandomWalkCoefficient,
  kAllanMinimum,
  kBiasRandomWalkCoefficient,
};
const char* SpecConventionName(SpecConvention c);  // "one_sided_density", ...
// The IEEE 952 term the convention describes (N, B or K).
NoiseTerm SpecConventionTerm(SpecConvention c);

enum class SpecKind { kTyp, kMin, kMax, kUnstated, kConfig };
const char* SpecKindName(SpecKind k);  // "typ", "min", "max", "unstated", "config".

// The unit of a figure: its SI factor and SI unit, or nullopt for a unit not in the table.
struct SpecUnit {
  double si_factor = 1.0;  // value_si = value * si_factor.
  std::string si_unit;     // "rad/s/sqrt(Hz)", "m/s^2", ...
};
std::optional<SpecUnit> SpecUnitOf(std::string_view unit);

struct SpecDocument {
  std::string id;        // Referenced by figures ("source").
  std::string title;     // "MPU-6000 and MPU-6050 Product Specification".
  std::string number;    // "PS-MPU-6000A-00" (or a file path for a published config).
  std::string revision;  // "3.4" (or a commit).
  std::string date;      // ISO 8601 when known.
  std::string read_at;   // Where the figures were read (URL or repository path).
};

struct SpecFigure {
  std::string source;                     // SpecDocument::id.
  SensorKind sensor = SensorKind::kNone;  // kGyroscope or kAccelerometer.
  SpecConvention convention = SpecConvention::kOneSidedDensity;
  SpecKind kind = SpecKind::kTyp;
  double value = std::nan("");  // As printed, in `unit`.
  std::string unit;
  std::string printed;           // The figure as printed, e.g. "0.005 º/s/√Hz".
  std::string page;              // "12".
  std::string table;             // "6.1 Gyroscope Specifications: Rate Noise Spectral Density".
  std::string conditions;        // "at 10 Hz, FS_SEL=0".
  std::string key;               // config figures: the file's key ("accelerometer_random_walk").
  int64_t line = 0, column = 0;  // Where the figure is in the library (for messages).

  NoiseTerm term() const { return SpecConventionTerm(convention); }
  double ValueSi() const;  // value * SpecUnitOf(unit)->si_factor.
  // The IEEE 952 coefficient in SI: N (d / sqrt(2) for a one-sided density), B's Allan
  // minimum, or K.
  double CoefficientSi() const;
};

struct SpecPart {
  std::string part;                // "MPU6050".
  std::vector<std::string> names;  // Other spellings accepted ("MPU-6050").
  std::string manufacturer;
  std::vector<SpecDocument> documents;
  std::vector<SpecFigure> figures;

  const SpecDocument* Document(const std::string& id) const;
};

struct SpecLibrary {
  std::string file;
  std::vector<SpecPart> parts;

  // The part named `name` (case and '-', '_', ' ' ignored: "mpu-6050" finds MPU6050);
  // an input error listing the parts otherwise.
  Result<const SpecPart*> Find(std::string_view name) const;
};

// Parses a library (schema "metro.specs/1"; datasets/specs/schema.json). Errors at
// file:line:column: not JSON, another schema, a missing or unknown member (naming the
// supported ones), a sensor, convention, kind or unit not in the lists above (naming them), a
// unit that does not fit the convention and sensor, a negative or non-finite value, a figure
// whose source is not a document of its part, a part named twice.
Result<SpecLibrary> ParseSpecLibrary(std::string_view text, const std::string& file);
Result<SpecLibrary> LoadSpecLibrary(const std::string& path);

// The figures of `part` by source document, in library order: one column per document.
struct SpecSourceValue {
  std::string source;
  std::optional<double> value;  // The coefficient in SI (N, B's Allan minimum or K).
};
struct SpecSourceRow {
  SensorKind sensor = SensorKind::kNone;
  NoiseTerm term = NoiseTerm::kRandomWalk;
  std::string kalibr_key;  // "gyroscope_noise_density", ...; empty for B.
  std::string si_unit;
  std::vector<SpecSourceValue> values;  // One per document of the part.
};
// Rows for gyroscope/accelerometer x N, B, K that at least one document gives. Where a
// document gives several figures of one row, the first in the library counts.
std::vector<SpecSourceRow> CompareSpecSources(const SpecPart& part);
// The table of CompareSpecSources: each source's value and its ratio to `reference` (a
// document id of the part; empty: the first document).
Result<std::string> SpecSourcesTable(const SpecPart& part, const std::string& reference);

// Datasheet -> Kalibr imu.yaml (docs/specs.md "To Kalibr"), from the part's figures of kind
// typ, unstated or max (never config: those are someone's file) in the document `source`
// (empty: the first datasheet document with N figures). Assumptions, written in the file:
// N = d / sqrt(2) for a one-sided density (docs/noise.md section 5), deg -> rad by pi/180, ug
// -> m/s^2 by 9.80665e-6, the figure taken for every axis, the rate and topic the user's.
// K is refused by name when the document gives none (a bias instability is not a random
// walk: metro does not derive K from it) unless `partial`, which writes the file without the
// K keys and says so. Errors (input): no such document, no N figure for a sensor.
struct SpecToKalibrOptions {
  std::string source;
  double update_rate_hz = std::nan("");
  std::string rostopic = "/imu0";
  bool partial = false;
};
Result<std::string> SpecToKalibrYaml(const SpecPart& part, const SpecToKalibrOptions& options,
                                     const std::string& library_file);

}  // namespace metro
