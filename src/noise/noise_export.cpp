#include "metro/noise/noise_export.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <optional>

#include "noise/noise_export_formats.hpp"

namespace metro {
namespace {

// The 95 % coverage factor of the normal distribution (JCGM 100:2008 G.1.3, Table G.1).
constexpr double kK95 = 1.959963984540054;

// One term of one axis in SI (rad/s or m/s^2 based units) and as the report states it.
struct AxisTerm {
  std::string quantity;
  char axis = 0;
  double value = std::nan("");
  double u = std::nan("");
  double value_report = std::nan("");  // As in the report, its unit below.
  double u_report = std::nan("");
  std::string unit_report;
};

// Why `axis`'s `term` is not a value metro may write; empty when it is.
std::string RefusalReason(const NoiseExportAxis& axis, NoiseTerm term) {
  const AllanReport& a = axis.allan;
  if (!a.ok()) return "the Allan analysis failed: " + a.error;
  if (a.fit_error) return "the noise terms could not be fitted: " + *a.fit_error;
  const AllanNoiseTermReport& t = a.term(term);
  if (!t.supported || std::isnan(t.value)) {
    if (term == NoiseTerm::kRateRandomWalk && a.b_k && a.b_k->joint) {
      return "the record cannot separate B and K (allan.b_k.joint): K is not in the model";
    }
    return "the fit does not support the term (value null, supported false)";
  }
  if (t.model_rejected.value_or(false)) {
    return "the IEEE 952 model was rejected over the fitted range (allan.model_check, "
           "model_rejected true)";
  }
  if (!(t.u >= 0.0)) return "the term has no uncertainty (u null)";
  return {};
}

// The factor from the quantity's unit to rad/s (gyroscope) or m/s^2 (accelerometer).
Result<double> SiFactor(const NoiseExportAxis& axis, SensorKind sensor) {
  const Unit* unit = UnitBySymbol(axis.unit);
  const char* target = sensor == SensorKind::kGyroscope ? "rad/s" : "m/s^2";
  const std::optional<double> f =
      unit != nullptr ? ConversionFactor(*unit, *UnitBySymbol(target)) : std::nullopt;
  if (!f) {
    return MakeError(
        fmt::format("{} is in {}: the estimators' files take {} (an SI scale); export a calibrated "
                    "session's report",
                    axis.quantity, axis.unit.empty() ? "no unit" : axis.unit, target));
  }
  return *f;
}

// The term of every axis of `sensor`, in SI, sorted by axis; refused by name.
Result<std::vector<AxisTerm>> SensorTerms(const NoiseExportInput& input, SensorKind sensor,
                                          NoiseTerm term) {
  std::vector<AxisTerm> out;
  for (const NoiseExportAxis& a : input.axes) {
    const ColumnInfo info = ClassifyColumn(a.quantity);
    if (info.sensor != sensor) continue;
    if (std::any_of(out.begin(), out.end(), [&](const AxisTerm& t) { return t.axis == info.axis; }))
      continue;  // One quantity per axis: the first in the report's order.
    const std::string why = RefusalReason(a, term);
    if (!why.empty()) {
      return MakeError(
          fmt::format("{} {} ({}): not resolved by the record: {}; metro does not "
                      "fill it in",
                      a.quantity, NoiseTermKey(term), NoiseTermSymbol(term), why));
    }
    Result<double> f = SiFactor(a, sensor);
    if (!f.ok()) return f.error();
    const AllanNoiseTermReport& t = a.allan.term(term);
    out.push_back(
        {a.quantity, info.axis, t.value * f.value(), t.u * f.value(), t.value, t.u, t.unit});
  }
  if (out.empty()) {
    return MakeError(fmt::format("the record has no {} axis with an Allan analysis (--allan)",
                                 sensor == SensorKind::kGyroscope ? "gyroscope" : "accelerometer"));
  }
  std::sort(out.begin(), out.end(),
            [](const AxisTerm& a, const AxisTerm& b) { return a.axis < b.axis; });
  return out;
}

std::string Quantities(const std::vector<AxisTerm>& terms) {
  std::string s;
  for (const AxisTerm& t : terms) s += (s.empty() ? "" : " ") + t.quantity;
  return s;
}

// The value over the axes: max (the largest and its own u) or rms (u by JCGM 100:2008 5.1.2
// with uncorrelated axes: u(r)^2 = sum (v_i u_i)^2 / (n r)^2).
AxisTerm Reduce(const std::vector<AxisTerm>& terms, AxisReduction reduction, NoiseTerm term,
                std::string* from) {
  if (reduction == AxisReduction::kMax) {
    const AxisTerm& m =
        *std::max_element(terms.begin(), terms.end(),
                          [](const AxisTerm& a, const AxisTerm& b) { return a.value < b.value; });
    *from =
        fmt::format("max over {}: {} {} = {:.6g} {} +/- {:.2g} (k = 1)", Quantities(terms),
                    m.quantity, NoiseTermSymbol(term), m.value_report, m.unit_report, m.u_report);
    return m;
  }
  double sum2 = 0.0, var_num = 0.0;
  for (const AxisTerm& t : terms) {
    sum2 += t.value * t.value;
    var_num += t.value * t.value * t.u * t.u;
  }
  const double n = static_cast<double>(terms.size());
  AxisTerm r;
  r.quantity = Quantities(terms);
  r.value = std::sqrt(sum2 / n);
  r.u = r.value > 0.0 ? std::sqrt(var_num) / (n * r.value) : 0.0;
  *from = fmt::format("rms over {} (each {} from the report)", r.quantity, NoiseTermSymbol(term));
  return r;
}

// The file's value of a continuous SI term under `kind`, and the same factor for its u.
double KindFactor(ExportValueKind kind, double value_si, double rate_hz, double px4_rate_hz) {
  switch (kind) {
    case ExportValueKind::kContinuous:
      return 1.0;
    case ExportValueKind::kPx4PerStep:
      return std::sqrt(px4_rate_hz);
    case ExportValueKind::kSampleVariance:
      return value_si * rate_hz;  // v^2 f: d(v^2 f)/dv = 2 v f, applied to u below.
  }
  return 1.0;
}

ExportedNoiseValue MakeValue(const ExportKeySpec& spec, const AxisTerm& t, const std::string& from,
                             double rate_hz, double px4_rate_hz) {
  ExportedNoiseValue v;
  v.key = spec.key;
  v.sensor = spec.sensor;
  v.term = spec.term;
  const double f = KindFactor(spec.kind, t.value, rate_hz, px4_rate_hz);
  v.value = t.value * f;
  v.u = spec.kind == ExportValueKind::kSampleVariance ? 2.0 * t.value * rate_hz * t.u : t.u * f;
  v.low95 = v.value - kK95 * v.u;
  v.high95 = v.value + kK95 * v.u;
  v.unit = ExportUnit(spec);
  v.convention = ExportConvention(spec, px4_rate_hz);
  v.from = from;
  return v;
}

// The record's rate: the first axis's allan.sample_period.rate_hz (all must agree to 1e-6).
Result<double> RecordRate(const NoiseExportInput& input) {
  double rate = std::nan("");
  for (const NoiseExportAxis& a : input.axes) {
    const SensorKind s = ClassifyColumn(a.quantity).sensor;
    if (!a.allan.ok() || (s != SensorKind::kGyroscope && s != SensorKind::kAccelerometer)) continue;
    const double r = a.allan.sample_period.rate_hz;
    if (!(r > 0.0)) continue;
    if (std::isnan(rate)) {
      rate = r;
    } else if (std::fabs(r - rate) > 1e-6 * rate) {
      return MakeError(
          fmt::format("the axes were sampled at different rates ({} and {} Hz): "
                      "one file holds one update rate",
                      rate, r));
    }
  }
  if (std::isnan(rate)) return MakeError("no axis states its sample rate (allan.sample_period)");
  return rate;
}

}  // namespace

const char* NoiseExportFormatName(NoiseExportFormat format) {
  switch (format) {
    case NoiseExportFormat::kKalibr:
      return "kalibr";
    case NoiseExportFormat::kOpenVins:
      return "openvins";
    case NoiseExportFormat::kBasalt:
      return "basalt";
    case NoiseExportFormat::kVins:
      return "vins";
    case NoiseExportFormat::kOrbSlam3:
      return "orbslam3";
    case NoiseExportFormat::kGtsam:
      return "gtsam";
    case NoiseExportFormat::kPx4Ekf2:
      return "px4-ekf2";
    case NoiseExportFormat::kRos:
      return "ros";
  }
  return "?";
}

Result<NoiseExportFormat> ParseNoiseExportFormat(std::string_view name) {
  std::string names;
  for (NoiseExportFormat f : kAllNoiseExportFormats) {
    if (name == NoiseExportFormatName(f)) return f;
    names += (names.empty() ? "" : ", ") + std::string(NoiseExportFormatName(f));
  }
  return MakeError(
      fmt::format("unknown noise export format '{}'; expected one of {}", name, names));
}

const char* AxisReductionName(AxisReduction reduction) {
  return reduction == AxisReduction::kMax ? "max" : "rms";
}

Result<AxisReduction> ParseAxisReduction(std::string_view name) {
  if (name == "max") return AxisReduction::kMax;
  if (name == "rms") return AxisReduction::kRms;
  return MakeError(fmt::format("unknown axis reduction '{}'; expected max or rms", name));
}

bool NoiseExportOptions::IsValid(std::string* why) const {
  if (!(px4_predict_rate_hz > 0.0) || !std::isfinite(px4_predict_rate_hz)) {
    *why = "px4_predict_rate_hz must be a positive number of Hz";
    return false;
  }
  // A ROS graph resource name (wiki.ros.org/Names): letters, digits, _, / and ~.
  const bool ros_name =
      !rostopic.empty() && std::all_of(rostopic.begin(), rostopic.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '/' || c == '~';
      });
  if (!ros_name) {
    *why = "rostopic '" + rostopic + "' is not a ROS name (letters, digits, _, / and ~)";
    return false;
  }
  return true;
}

std::optional<StandardNoiseName> StandardNoiseNameOf(NoiseTerm term,
                                                     const AllanNoiseTermReport& report) {
  const bool white = term == NoiseTerm::kRandomWalk;
  if (!white && term != NoiseTerm::kRateRandomWalk) return std::nullopt;
  const std::string suffix = white ? "*sqrt(s)" : "/sqrt(s)";
  const std::string& unit = report.unit;
  if (unit.size() <= suffix.size() ||
      unit.compare(unit.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return std::nullopt;
  }
  const Unit* q = UnitBySymbol(unit.substr(0, unit.size() - suffix.size()));
  if (q == nullptr) return std::nullopt;
  const bool gyro = q->dimension == Dimension::kAngularRate;
  if (!gyro && q->dimension != Dimension::kAcceleration) return std::nullopt;
  const std::optional<double> f = ConversionFactor(*q, *UnitBySymbol(gyro ? "rad/s" : "m/s^2"));
  if (!f) return std::nullopt;
  StandardNoiseName s;
  s.name = white ? (gyro ? "angle_random_walk" : "velocity_random_walk")
                 : (gyro ? "rate_random_walk" : "acceleration_random_walk");
  s.kalibr_key = std::string(gyro ? "gyroscope" : "accelerometer") +
                 (white ? "_noise_density" : "_random_walk");
  s.unit = white ? (gyro ? "rad/s/sqrt(Hz)" : "m/s^2/sqrt(Hz)")
                 : (gyro ? "rad/s^2/sqrt(Hz)" : "m/s^3/sqrt(Hz)");
  s.value = report.value * *f;
  s.u = report.u * *f;
  if (white) {  // One-sided density d = sqrt(2) N (noise_units.hpp).
    s.density_one_sided = std::sqrt(2.0) * s.value;
    s.u_density_one_sided = std::sqrt(2.0) * s.u;
  }
  return s;
}

double DiscreteWhiteSigma(double density, double rate_hz) { return density * std::sqrt(rate_hz); }

double DiscreteBiasWalkSigma(double walk, double rate_hz) { return walk / std::sqrt(rate_hz); }

Result<NoiseExport> ExportedNoiseValues(const NoiseExportInput& input,
                                        const NoiseExportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  NoiseExport out;
  out.format = options.format;
  Result<double> rate = RecordRate(input);
  if (!rate.ok()) return rate.error();
  out.rate_hz = rate.value();
  for (const ExportKeyGroup& group : ExportKeyGroups(options.format)) {
    Result<std::vector<AxisTerm>> terms = SensorTerms(input, group.sensor, group.term);
    if (!terms.ok()) return terms.error();
    if (group.per_axis) {
      if (terms.value().size() != 3) {
        return MakeError(
            fmt::format("{} holds one value per axis and needs the three axes; the "
                        "record has {}",
                        NoiseExportFormatName(options.format), Quantities(terms.value())));
      }
      for (size_t i = 0; i < 3; ++i) {
        const AxisTerm& t = terms.value()[i];
        const std::string from =
            fmt::format("{} {} = {:.6g} {} +/- {:.2g} (k = 1)", t.quantity,
                        NoiseTermSymbol(group.term), t.value_report, t.unit_report, t.u_report);
        out.values.push_back(
            MakeValue(group.keys[i], t, from, out.rate_hz, options.px4_predict_rate_hz));
      }
    } else {
      std::string from;
      const AxisTerm r = Reduce(terms.value(), options.reduction, group.term, &from);
      out.values.push_back(
          MakeValue(group.keys[0], r, from, out.rate_hz, options.px4_predict_rate_hz));
    }
  }
  return out;
}

Result<NoiseExport> ExportNoise(const NoiseExportInput& input, const NoiseExportOptions& options) {
  Result<NoiseExport> values = ExportedNoiseValues(input, options);
  if (!values.ok()) return values.error();
  NoiseExport out = std::move(values).value();
  out.text = ExportText(out, input.source, options);
  return out;
}

}  // namespace metro
