#include "metro/noise/spec_library.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <set>

#include "core/json_reader.hpp"
#include "metro/core/file.hpp"

namespace metro {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Standard gravity (CGPM 1901, exact), the g of every ug and mg figure (the same value as
// calibration/imu_model.hpp's, which this layer may not include).
constexpr double kG0 = 9.80665;

struct UnitRow {
  const char* unit;
  double si_factor;
  const char* si_unit;
};
// docs/specs.md "Units"; exact factors (g0 = 9.80665 m/s^2, deg = pi/180 rad, h = 3600 s).
const UnitRow kUnits[] = {
    {"deg/s/sqrt(Hz)", kPi / 180.0, "rad/s/sqrt(Hz)"},
    {"mdps/sqrt(Hz)", kPi / 180.0e3, "rad/s/sqrt(Hz)"},
    {"rad/s/sqrt(Hz)", 1.0, "rad/s/sqrt(Hz)"},
    {"deg/sqrt(h)", kPi / 180.0 / 60.0, "rad/s/sqrt(Hz)"},
    {"ug/sqrt(Hz)", 1e-6 * kG0, "m/s^2/sqrt(Hz)"},
    {"mg/sqrt(Hz)", 1e-3 * kG0, "m/s^2/sqrt(Hz)"},
    {"m/s^2/sqrt(Hz)", 1.0, "m/s^2/sqrt(Hz)"},
    {"m/s/sqrt(h)", 1.0 / 60.0, "m/s^2/sqrt(Hz)"},
    {"deg/h", kPi / 180.0 / 3600.0, "rad/s"},
    {"deg/s", kPi / 180.0, "rad/s"},
    {"rad/s", 1.0, "rad/s"},
    {"ug", 1e-6 * kG0, "m/s^2"},
    {"mg", 1e-3 * kG0, "m/s^2"},
    {"m/s^2", 1.0, "m/s^2"},
    {"rad/s^2/sqrt(Hz)", 1.0, "rad/s^2/sqrt(Hz)"},
    {"m/s^3/sqrt(Hz)", 1.0, "m/s^3/sqrt(Hz)"},
};

const SpecConvention kConventions[] = {
    SpecConvention::kOneSidedDensity, SpecConvention::kRandomWalkCoefficient,
    SpecConvention::kAllanMinimum, SpecConvention::kBiasRandomWalkCoefficient};
const SpecKind kKinds[] = {SpecKind::kTyp, SpecKind::kMin, SpecKind::kMax, SpecKind::kUnstated,
                           SpecKind::kConfig};

// The SI unit a figure of `convention` for `sensor` must convert to.
std::string ExpectedSiUnit(SensorKind sensor, SpecConvention convention) {
  const bool gyro = sensor == SensorKind::kGyroscope;
  switch (convention) {
    case SpecConvention::kOneSidedDensity:
    case SpecConvention::kRandomWalkCoefficient:
      return gyro ? "rad/s/sqrt(Hz)" : "m/s^2/sqrt(Hz)";
    case SpecConvention::kAllanMinimum:
      return gyro ? "rad/s" : "m/s^2";
    case SpecConvention::kBiasRandomWalkCoefficient:
      return gyro ? "rad/s^2/sqrt(Hz)" : "m/s^3/sqrt(Hz)";
  }
  return {};
}

std::string Normalized(std::string_view name) {
  std::string s;
  for (char c : name) {
    if (c == '-' || c == '_' || c == ' ') continue;
    s += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  return s;
}

// Fails `c` when it has a member not in `known`; true when all are known.
bool OnlyKnown(const JsonCursor& c, std::initializer_list<const char*> known) {
  if (!c.IsObject()) {
    c.Fail("an object");
    return false;
  }
  for (const std::string& k : c.Keys()) {
    if (std::none_of(known.begin(), known.end(), [&](const char* n) { return k == n; })) {
      std::string list;
      for (const char* n : known) list += fmt::format("{}{}", list.empty() ? "" : ", ", n);
      c[k].Fail(fmt::format("no member '{}' (a spec entry holds {})", k, list));
      return false;
    }
  }
  return true;
}

template <typename E, size_t n>
E Named(const JsonCursor& c, const E (&all)[n], const char* (*name)(E), const char* what) {
  const std::string s = c.String();
  for (E e : all) {
    if (s == name(e)) return e;
  }
  std::string list;
  for (E e : all) list += fmt::format("{}{}", list.empty() ? "" : ", ", name(e));
  if (c.ok()) c.Fail(fmt::format("a {} ({}), not '{}'", what, list, s));
  return all[0];
}

const char* SensorName(SensorKind s) {
  return s == SensorKind::kGyroscope ? "gyroscope" : "accelerometer";
}

SpecDocument ReadDocument(const JsonCursor& c) {
  SpecDocument d;
  if (!OnlyKnown(c, {"id", "title", "number", "revision", "date", "read_at"})) return d;
  d.id = c["id"].String();
  d.title = c["title"].String();
  d.number = c["number"].String();
  d.revision = c["revision"].String();
  d.date = c["date"].OptionalString().value_or("");
  d.read_at = c["read_at"].String();
  return d;
}

SpecFigure ReadFigure(const JsonCursor& c, const JsonDocument& doc,
                      const std::vector<JsonPathStep>& path) {
  SpecFigure f;
  std::tie(f.line, f.column) = doc.LineColumnOf(path);
  if (!OnlyKnown(c, {"source", "sensor", "convention", "kind", "value", "unit", "printed", "page",
                     "table", "conditions", "key"})) {
    return f;
  }
  f.source = c["source"].String();
  const std::string sensor = c["sensor"].String();
  if (sensor == "gyroscope") {
    f.sensor = SensorKind::kGyroscope;
  } else if (sensor == "accelerometer") {
    f.sensor = SensorKind::kAccelerometer;
  } else if (c.ok()) {
    c["sensor"].Fail("\"gyroscope\" or \"accelerometer\", not '" + sensor + "'");
  }
  f.convention = Named(c["convention"], kConventions, SpecConventionName, "convention");
  f.kind = Named(c["kind"], kKinds, SpecKindName, "kind");
  f.value = c["value"].Number();
  f.unit = c["unit"].String();
  f.printed = c["printed"].String();
  f.page = c["page"].String();
  f.table = c["table"].String();
  f.conditions = c["conditions"].OptionalString().value_or("");
  f.key = c["key"].OptionalString().value_or("");
  if (!c.ok()) return f;
  if (!std::isfinite(f.value) || f.value < 0.0) {
    c["value"].Fail("a finite non-negative number (a noise figure)");
  }
  const std::optional<SpecUnit> u = SpecUnitOf(f.unit);
  const std::string want = ExpectedSiUnit(f.sensor, f.convention);
  if (c.ok() && (!u || u->si_unit != want)) {
    std::string list;
    for (const UnitRow& r : kUnits) {
      if (r.si_unit == want) list += fmt::format("{}{}", list.empty() ? "" : ", ", r.unit);
    }
    c["unit"].Fail(fmt::format("a unit of a {} {} figure ({}), not '{}'", SensorName(f.sensor),
                               SpecConventionName(f.convention), list, f.unit));
  }
  return f;
}

SpecPart ReadPart(const JsonCursor& c, const JsonDocument& doc, size_t index) {
  SpecPart p;
  if (!OnlyKnown(c, {"part", "names", "manufacturer", "documents", "figures"})) return p;
  p.part = c["part"].String();
  p.names = c["names"].Strings();
  p.manufacturer = c["manufacturer"].String();
  const JsonCursor docs = c["documents"];
  for (size_t i = 0; i < docs.Size(); ++i) p.documents.push_back(ReadDocument(docs[i]));
  const JsonCursor figs = c["figures"];
  if (!figs.IsArray()) figs.Fail("an array of figures");
  for (size_t i = 0; i < figs.Size() && c.ok(); ++i) {
    SpecFigure f =
        ReadFigure(figs[i], doc, {std::string("parts"), index, std::string("figures"), i});
    if (c.ok() && p.Document(f.source) == nullptr) {
      figs[i]["source"].Fail(
          fmt::format("the id of one of {}'s documents, not '{}'", p.part, f.source));
    }
    p.figures.push_back(std::move(f));
  }
  return p;
}

SpecLibrary ReadLibrary(const JsonCursor& root, const JsonDocument& doc) {
  SpecLibrary lib;
  if (!OnlyKnown(root, {"schema", "comment", "parts"})) return lib;
  const std::string schema = root["schema"].String();
  if (root.ok() && schema != "metro.specs/1") {
    root["schema"].Fail("\"metro.specs/1\", not '" + schema + "'");
  }
  const JsonCursor parts = root["parts"];
  if (!parts.IsArray()) parts.Fail("an array of parts");
  std::set<std::string> seen;
  for (size_t i = 0; i < parts.Size() && root.ok(); ++i) {
    SpecPart p = ReadPart(parts[i], doc, i);
    if (root.ok() && !seen.insert(Normalized(p.part)).second) {
      parts[i]["part"].Fail(fmt::format("a part named once, not '{}' again", p.part));
    }
    lib.parts.push_back(std::move(p));
  }
  return lib;
}

std::string KalibrKey(SensorKind sensor, NoiseTerm term) {
  const std::string s = sensor == SensorKind::kGyroscope ? "gyroscope" : "accelerometer";
  if (term == NoiseTerm::kRandomWalk) return s + "_noise_density";
  if (term == NoiseTerm::kRateRandomWalk) return s + "_random_walk";
  return {};
}

const SpecFigure* FirstFigure(const SpecPart& part, const std::string& source, SensorKind sensor,
                              NoiseTerm term, bool datasheet_only) {
  for (const SpecFigure& f : part.figures) {
    if (f.source != source || f.sensor != sensor || f.term() != term) continue;
    if (datasheet_only && f.kind == SpecKind::kConfig) continue;
    return &f;
  }
  return nullptr;
}

// The N figure of `sensor` in `source` for Kalibr, with the assumption line for the file.
Result<double> KalibrDensity(const SpecPart& part, const std::string& source, SensorKind sensor,
                             std::string* note) {
  const SpecFigure* f = FirstFigure(part, source, sensor, NoiseTerm::kRandomWalk, true);
  if (f == nullptr) {
    return MakeError(fmt::format("{} ({}): no {} noise figure (N) to convert", part.part, source,
                                 SensorName(sensor)));
  }
  const double n = f->CoefficientSi();
  *note = fmt::format("# {}: {} = {} ({}, {}, page {}, {}{}) -> {} x {:.12g}{} = {:.12g} {}\n",
                      KalibrKey(sensor, NoiseTerm::kRandomWalk), f->printed, f->value,
                      SpecKindName(f->kind), SpecConventionName(f->convention), f->page, f->table,
                      f->conditions.empty() ? "" : ", " + f->conditions, f->unit,
                      SpecUnitOf(f->unit)->si_factor,
                      f->convention == SpecConvention::kOneSidedDensity ? " / sqrt(2)" : "", n,
                      SpecUnitOf(f->unit)->si_unit);
  return n;
}

}  // namespace

const char* SpecConventionName(SpecConvention c) {
  switch (c) {
    case SpecConvention::kOneSidedDensity:
      return "one_sided_density";
    case SpecConvention::kRandomWalkCoefficient:
      return "random_walk_coefficient";
    case SpecConvention::kAllanMinimum:
      return "allan_minimum";
    case SpecConvention::kBiasRandomWalkCoefficient:
      return "bias_random_walk_coefficient";
  }
  return "";
}

NoiseTerm SpecConventionTerm(SpecConvention c) {
  switch (c) {
    case SpecConvention::kOneSidedDensity:
    case SpecConvention::kRandomWalkCoefficient:
      return NoiseTerm::kRandomWalk;
    case SpecConvention::kAllanMinimum:
      return NoiseTerm::kBiasInstability;
    case SpecConvention::kBiasRandomWalkCoefficient:
      return NoiseTerm::kRateRandomWalk;
  }
  return NoiseTerm::kRandomWalk;
}

const char* SpecKindName(SpecKind k) {
  switch (k) {
    case SpecKind::kTyp:
      return "typ";
    case SpecKind::kMin:
      return "min";
    case SpecKind::kMax:
      return "max";
    case SpecKind::kUnstated:
      return "unstated";
    case SpecKind::kConfig:
      return "config";
  }
  return "";
}

std::optional<SpecUnit> SpecUnitOf(std::string_view unit) {
  for (const UnitRow& r : kUnits) {
    if (unit == r.unit) return SpecUnit{r.si_factor, r.si_unit};
  }
  return std::nullopt;
}

double SpecFigure::ValueSi() const {
  const std::optional<SpecUnit> u = SpecUnitOf(unit);
  return u ? value * u->si_factor : std::nan("");
}

double SpecFigure::CoefficientSi() const {
  // docs/noise.md section 5: a one-sided density d is sqrt(2) N.
  return convention == SpecConvention::kOneSidedDensity ? ValueSi() / std::sqrt(2.0) : ValueSi();
}

const SpecDocument* SpecPart::Document(const std::string& id) const {
  for (const SpecDocument& d : documents) {
    if (d.id == id) return &d;
  }
  return nullptr;
}

Result<const SpecPart*> SpecLibrary::Find(std::string_view name) const {
  const std::string want = Normalized(name);
  std::string list;
  for (const SpecPart& p : parts) {
    if (Normalized(p.part) == want) return &p;
    for (const std::string& n : p.names) {
      if (Normalized(n) == want) return &p;
    }
    list += fmt::format("{}{}", list.empty() ? "" : ", ", p.part);
  }
  return MakeError(fmt::format("{}: no part '{}' in the spec library; it holds {}", file,
                               std::string(name), list));
}

Result<SpecLibrary> ParseSpecLibrary(std::string_view text, const std::string& file) {
  Result<JsonDocument> doc = JsonDocument::Parse(std::string(text), file);
  if (!doc.ok()) return doc.error();
  const JsonCursor root(doc.value());
  SpecLibrary lib = ReadLibrary(root, doc.value());
  if (!root.ok()) return root.error();
  lib.file = file;
  return lib;
}

Result<SpecLibrary> LoadSpecLibrary(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok()) return text.error();
  return ParseSpecLibrary(text.value(), path);
}

std::vector<SpecSourceRow> CompareSpecSources(const SpecPart& part) {
  std::vector<SpecSourceRow> rows;
  for (SensorKind sensor : {SensorKind::kAccelerometer, SensorKind::kGyroscope}) {
    for (NoiseTerm term :
         {NoiseTerm::kRandomWalk, NoiseTerm::kBiasInstability, NoiseTerm::kRateRandomWalk}) {
      SpecSourceRow row{sensor, term, KalibrKey(sensor, term), "", {}};
      bool any = false;
      for (const SpecDocument& d : part.documents) {
        const SpecFigure* f = FirstFigure(part, d.id, sensor, term, false);
        row.values.push_back({d.id, f ? std::optional<double>(f->CoefficientSi()) : std::nullopt});
        if (f != nullptr) {
          any = true;
          row.si_unit = SpecUnitOf(f->unit)->si_unit;
        }
      }
      if (any) rows.push_back(std::move(row));
    }
  }
  return rows;
}

Result<std::string> SpecSourcesTable(const SpecPart& part, const std::string& reference) {
  if (part.documents.empty()) return MakeError(part.part + ": no documents");
  const std::string ref = reference.empty() ? part.documents.front().id : reference;
  const auto ref_it = std::find_if(part.documents.begin(), part.documents.end(),
                                   [&](const SpecDocument& d) { return d.id == ref; });
  if (ref_it == part.documents.end()) {
    std::string ids;
    for (const SpecDocument& d : part.documents) ids += (ids.empty() ? "" : ", ") + d.id;
    return MakeError(fmt::format("--reference {}: not a document of {} ({})", ref, part.part, ids));
  }
  const size_t r = static_cast<size_t>(ref_it - part.documents.begin());
  std::string s = fmt::format(
      "{}: published noise figures as IEEE 952 coefficients in SI "
      "(N = d/sqrt(2) for a one-sided density), ratio to {}\n",
      part.part, ref);
  for (const SpecDocument& d : part.documents) {
    s += fmt::format("  {}: {}, {} rev. {}\n", d.id, d.title, d.number, d.revision);
  }
  for (const SpecSourceRow& row : CompareSpecSources(part)) {
    const std::string name = row.kalibr_key.empty()
                                 ? fmt::format("{}_allan_minimum", SensorName(row.sensor))
                                 : row.kalibr_key;
    s += fmt::format("{:<30} {}\n", name, row.si_unit);
    for (const SpecSourceValue& v : row.values) {
      const std::optional<double> base = row.values[r].value;
      if (!v.value) {
        s += fmt::format("  {:<24} {:>14}\n", v.source, "-");
      } else if (base && *base > 0.0) {
        s +=
            fmt::format("  {:<24} {:>14.6g}  ratio {:.4g}\n", v.source, *v.value, *v.value / *base);
      } else {
        s += fmt::format("  {:<24} {:>14.6g}\n", v.source, *v.value);
      }
    }
  }
  return s;
}

Result<std::string> SpecToKalibrYaml(const SpecPart& part, const SpecToKalibrOptions& o,
                                     const std::string& library_file) {
  if (!(o.update_rate_hz > 0.0) || !std::isfinite(o.update_rate_hz)) {
    return MakeError(
        "--update-rate-hz: expected the rate the IMU is read at, in Hz (a datasheet gives a "
        "range of output data rates, not the one you use)");
  }
  std::string source = o.source;
  if (source.empty()) {
    for (const SpecDocument& d : part.documents) {
      if (FirstFigure(part, d.id, SensorKind::kGyroscope, NoiseTerm::kRandomWalk, true) ||
          FirstFigure(part, d.id, SensorKind::kAccelerometer, NoiseTerm::kRandomWalk, true)) {
        source = d.id;
        break;
      }
    }
  }
  const SpecDocument* doc = part.Document(source);
  if (doc == nullptr) {
    return MakeError(fmt::format("{}: no datasheet document with noise figures{}", part.part,
                                 o.source.empty() ? "" : " named " + o.source));
  }
  std::string notes[2];
  Result<double> acc = KalibrDensity(part, source, SensorKind::kAccelerometer, &notes[0]);
  if (!acc.ok()) return acc.error();
  Result<double> gyr = KalibrDensity(part, source, SensorKind::kGyroscope, &notes[1]);
  if (!gyr.ok()) return gyr.error();
  const SpecFigure* k_acc =
      FirstFigure(part, source, SensorKind::kAccelerometer, NoiseTerm::kRateRandomWalk, true);
  const SpecFigure* k_gyr =
      FirstFigure(part, source, SensorKind::kGyroscope, NoiseTerm::kRateRandomWalk, true);
  std::vector<std::string> missing;
  if (k_acc == nullptr) missing.push_back("accelerometer_random_walk");
  if (k_gyr == nullptr) missing.push_back("gyroscope_random_walk");
  const std::string why = fmt::format(
      "{} ({} rev. {}) gives no bias random walk (K); an in-run bias stability is a minimum "
      "of the Allan deviation, not a random walk, and metro does not derive K from it",
      part.part, doc->number, doc->revision);
  if (!missing.empty() && !o.partial) {
    return MakeError(
        fmt::format("{}: refused: {}; measure K (characterize SESSION --allan, "
                    "then noise-export) or write the file without it (--partial)",
                    fmt::join(missing, ", "), why));
  }
  std::string s = fmt::format(
      "# Kalibr imu.yaml from a datasheet, written by metro (characterize noise-export "
      "--from-spec {})\n# Source: {}, {} rev. {}{} ({}), read at {}; library {}\n"
      "# Assumptions: a datasheet noise density d is one-sided, Kalibr's noise density is the "
      "continuous\n# white sigma N with two-sided PSD N^2, so N = d / sqrt(2) (docs/noise.md "
      "section 5);\n# deg = pi/180 rad; ug = 1e-6 x 9.80665 m/s^2 (standard gravity); the "
      "figure holds for every axis;\n# a typ figure describes a typical part, not this one; "
      "update_rate and rostopic are the user's.\n",
      part.part, doc->title, doc->number, doc->revision, doc->date.empty() ? "" : ", " + doc->date,
      part.manufacturer, doc->read_at, library_file);
  s += notes[0] + notes[1];
  if (!missing.empty()) {
    s += fmt::format(
        "# NOT WRITTEN: {}: {}.\n# Kalibr needs them: this file is incomplete "
        "(--partial).\n",
        fmt::join(missing, ", "), why);
  }
  s += fmt::format("accelerometer_noise_density: {:.17g}\n", acc.value());
  if (k_acc != nullptr)
    s += fmt::format("accelerometer_random_walk: {:.17g}\n", k_acc->CoefficientSi());
  s += fmt::format("gyroscope_noise_density: {:.17g}\n", gyr.value());
  if (k_gyr != nullptr)
    s += fmt::format("gyroscope_random_walk: {:.17g}\n", k_gyr->CoefficientSi());
  s += fmt::format("rostopic: {}\nupdate_rate: {:.17g}\n", o.rostopic, o.update_rate_hz);
  return s;
}

}  // namespace metro
