#include "metro/calibration/calibration_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string_view>
#include <utility>

#include "metro/core/rounding.hpp"
#include "metro/core/terminal_text.hpp"

namespace metro {

namespace {

std::string Fixed(double v, int digits) { return fmt::format("{:.{}g}", v, digits); }

// JCGM 100:2008 7.2.2 concise notation: "826.6(5.0)", never "826.6026 (50)".
std::string ValueU(double v, double u) {
  if (u > 0) return ConciseNotation(v, u);
  return fmt::format("{:.7g} (fixed)", v);
}

}  // namespace

std::string FormatModelCheck(const ModelCheck& m, const std::string& indent) {
  std::string out = fmt::format("{}model check ({}): {}", indent, m.selection, m.status);
  if (m.chi2 >= 0) {
    out += fmt::format(", chi-square {:.4g} over {:.4g} dof", m.chi2, m.chi2_dof);
    if (m.p_value >= 0) out += fmt::format(" (p = {:.3g})", m.p_value);
  }
  if (m.model_rejected) out += ", model_rejected";
  out += "\n";
  for (const ModelComparison& c : m.comparisons) {
    out += fmt::format("{}  {} vs {}: ", indent, ModelKindName(c.smaller), ModelKindName(c.larger));
    if (c.test.empty()) {
      out += c.note + "\n";
      continue;
    }
    out += c.test == "F"
               ? fmt::format("F = {:.4g} (dof {:g}, {:.4g})", c.statistic, c.dof1, c.dof2)
               : fmt::format("chi-square difference {:.4g} (dof {:g})", c.statistic, c.dof1);
    out +=
        fmt::format(", p {}: {} {}\n",
                    c.p_value < 1e-16 ? std::string("< 1e-16") : fmt::format("= {:.3g}", c.p_value),
                    c.rejected ? "rejects" : "accepts", ModelKindName(c.smaller));
  }
  if (m.type_b) {
    out += fmt::format("{}  Type B in u: {} +-{:g} rad ({}, u = {:.4g} rad) from {}\n", indent,
                       fmt::join(m.type_b->terms, " "), m.type_b->half_width,
                       m.type_b->distribution, m.type_b->u, m.type_b->source);
  }
  if (!m.reason.empty()) out += fmt::format("{}  {}\n", indent, m.reason);
  return out;
}

std::vector<std::string> ModelRejectedConstants(const Calibration& cal) {
  std::vector<std::string> out;
  for (const TagCalibration& t : cal.tags) {
    for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
      if (c->has_value() && (*c)->model_check && (*c)->model_check->model_rejected) {
        out.push_back(fmt::format("sensor {} {}: {}", t.sensor, ImuSensorName((*c)->model.sensor),
                                  (*c)->model_check->reason));
      }
    }
  }
  return out;
}

namespace {

void ReportSensor(const SensorCalibration& c, std::string* out) {
  const SensorModel& m = c.model;
  const char* axes = "xyz";
  const bool u_unknown = UncertaintyUnknown(c);
  const auto value_u = [u_unknown](double v, double u) {
    return u_unknown ? fmt::format("{:.7g} (u unknown)", v) : ValueU(v, u);
  };
  *out += fmt::format("  {}: model {}, {} -> {}\n", ImuSensorName(m.sensor), ModelKindName(m.kind),
                      m.input_unit, m.output_unit);
  *out += fmt::format(
      "    calibrated = T K (raw - b); standard uncertainties (k = 1) in "
      "brackets; k95 = {:.3f} (dof {})\n",
      c.coverage_factor_95, c.dof);
  for (int a = 0; a < 3; ++a) {
    *out += fmt::format("    b_{}  = {} {}    k_{} = {} {}/{}\n", axes[a],
                        value_u(m.bias[a], c.bias_u[a]), m.input_unit, axes[a],
                        value_u(m.scale[a], c.scale_u[a]), m.output_unit, m.input_unit);
  }
  const char* const acc_names[] = {"a_yz", "a_zy", "a_zx"};
  const char* const gyr_names[] = {"g_yz", "g_zy", "g_xz", "g_zx", "g_xy", "g_yx"};
  const char* const* names = m.sensor == ImuSensor::kAccel ? acc_names : gyr_names;
  for (size_t i = 0; i < m.misalignment.size(); ++i) {
    const double u = i < c.misalignment_u.size() ? c.misalignment_u[i] : 0.0;
    *out += fmt::format("    {} = {} rad\n", names[i], value_u(m.misalignment[i], u));
  }
  if (m.has_temperature) {
    *out += fmt::format("    temperature: t_ref = {:.2f} degC\n", m.t_ref_c);
    for (int a = 0; a < 3; ++a) {
      *out += fmt::format("    b1_{} = {} {}/degC\n", axes[a],
                          value_u(m.bias_per_c[a], c.bias_per_c_u[a]), m.input_unit);
    }
  }
  const Eigen::Matrix3d mm = c.M();
  *out += "    M =\n";
  for (int r = 0; r < 3; ++r) {
    *out +=
        fmt::format("      [{:>14.7g} {:>14.7g} {:>14.7g}]   u [{:.2g} {:.2g} {:.2g}]\n", mm(r, 0),
                    mm(r, 1), mm(r, 2), c.matrix_u(r, 0), c.matrix_u(r, 1), c.matrix_u(r, 2));
  }
  *out += fmt::format("    residual rms {} {}, reduced chi^2 {:.3f}\n", Fixed(c.residual_rms, 4),
                      c.residual_unit, c.reduced_chi2);
  if (c.model_check) *out += FormatModelCheck(*c.model_check, "    ");
  for (const ResidualGroup& g : c.groups) {
    *out +=
        fmt::format("      {:<18} n = {:<6} rms {} {}\n", g.kind, g.count, Fixed(g.rms, 4), g.unit);
  }
  int counts[4] = {0, 0, 0, 0};  // SegmentKind order: static, table, rotation, steady
  for (const Segment& s : c.segments) ++counts[static_cast<int>(s.kind)];
  *out += fmt::format("    segments used: {} static, {} table, {} rotation\n", counts[0], counts[1],
                      counts[2]);
}

Status SetColumn(Tag* tag, const std::string& name, const std::string& unit,
                 std::vector<double> values) {
  for (Quantity& q : tag->quantities) {
    if (q.name == name) {
      q.unit = unit;
      q.origin = QuantityOrigin::kFile;
      q.values = std::move(values);
      return Status::Ok();
    }
  }
  Quantity q;
  q.name = name;
  q.unit = unit;
  q.origin = QuantityOrigin::kFile;
  q.values = std::move(values);
  tag->quantities.push_back(std::move(q));
  return Status::Ok();
}

const Quantity* FindColumn(const Tag& tag, const std::string& name) {
  for (const Quantity& q : tag.quantities) {
    if (q.name == name) return &q;
  }
  return nullptr;
}

// The first quantity of `tag` whose name starts with `prefix` ("ax_", "temp_"), or nullptr.
const Quantity* FindColumnPrefix(const Tag& tag, const std::string& prefix) {
  for (const Quantity& q : tag.quantities) {
    if (q.name.rfind(prefix, 0) == 0) return &q;
  }
  return nullptr;
}

// An error about a column of `session` at its header cell: file:line:field of the header field
// named `name`, or of the header's first field when `name` is empty or not in the header; the
// file alone for a session without a header line (a receiver capture, imu_tk).
Error HeaderCellError(const Session& session, const std::string& name, std::string message) {
  const InputDialect& d = session.input;
  if (d.header_line <= 0) return MakeError(session.path, 0, std::move(message));
  int64_t field = 1;
  for (size_t f = 0; f < d.header_names.size() && !name.empty(); ++f) {
    if (d.header_names[f] == name) {
      field = static_cast<int64_t>(f) + 1;
      break;
    }
  }
  return MakeError(session.path, d.header_line, field, std::move(message));
}

// Applies one sensor calibration to `tag` of `session`; with a temp_c column, *count receives
// how its temperatures met the validity range. A missing column is refused at the header cell
// of the column it would replace (the axis in another unit), else at the header line.
Status ApplySensor(const SensorCalibration& c, const TemperatureValidity& validity,
                   const Session& session, Tag* tag, std::optional<SensorTemperatureCount>* count) {
  const std::string& file = session.path;
  const ImuSensor sensor = c.model.sensor;
  const std::vector<std::string> in_names = InputColumns(sensor, c.model.input_unit);
  if (in_names.empty()) {
    return MakeError(file, 0,
                     fmt::format("sensor {}: the {} calibration's input unit '{}' is not a unit "
                                 "of the {}",
                                 tag->sensor, ImuSensorName(sensor), c.model.input_unit,
                                 ImuSensorLongName(sensor)));
  }
  const Quantity* in[3];
  for (int a = 0; a < 3; ++a) {
    const std::string& name = in_names[static_cast<size_t>(a)];
    in[a] = FindColumn(*tag, name);
    if (in[a] == nullptr) {
      // The nearest supported shape: the session's own column of that axis names its unit.
      const Quantity* other = FindColumnPrefix(*tag, name.substr(0, name.find('_') + 1));
      const std::string expected =
          fmt::format("expected the columns the calibration takes, {}", fmt::join(in_names, ", "));
      return HeaderCellError(
          session, other != nullptr ? other->name : "",
          fmt::format(
              "sensor {}: the {} calibration takes {} input (_{} columns) but the session "
              "has no {} column; {}",
              tag->sensor, ImuSensorName(sensor), c.model.input_unit,
              InputUnit(sensor, c.model.input_unit)->suffix, name,
              other != nullptr
                  ? fmt::format("it has {} (unit {}) instead: {} (a session in the unit "
                                "of the calibration's records)",
                                other->name, other->unit.empty() ? "?" : other->unit, expected)
                  : expected + " in the header"));
    }
  }
  const Quantity* temp = FindColumn(*tag, "temp_c");
  if (c.model.has_temperature && temp == nullptr) {
    const Quantity* other = FindColumnPrefix(*tag, "temp_");
    return HeaderCellError(
        session, other != nullptr ? other->name : "",
        fmt::format("sensor {}: the {} calibration has a temperature term but the session has no "
                    "temp_c column; {}expected temp_c (degC) in the header, as in the "
                    "calibration's records",
                    tag->sensor, ImuSensorName(sensor),
                    other != nullptr ? fmt::format("it has {} instead: ", other->name) : ""));
  }
  const size_t n = tag->size();
  std::vector<double> out[3];
  for (auto& o : out) o.resize(n);
  const Eigen::Matrix3d m = c.M();
  SensorTemperatureCount tc;
  tc.sensor = tag->sensor;
  tc.imu = sensor;
  tc.temperature_term = c.model.has_temperature;
  tc.t_ref_c = c.model.t_ref_c;
  tc.validity = validity;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d raw(in[0]->values[i], in[1]->values[i], in[2]->values[i]);
    double t = 0.0;
    if (temp != nullptr) {
      t = temp->values[i];
      ++tc.samples;
      if (std::isnan(t)) {
        ++tc.missing;
      } else if (t < validity.min_c) {
        ++tc.below;
      } else if (t > validity.max_c) {
        ++tc.above;
      }
      // The tag's rule (firmware metro_fw_apply): NaN -> t_ref_c, then clamped to the range.
      t = validity.Clamp(t, c.model.t_ref_c);
    }
    const Eigen::Vector3d y = m * (raw - c.model.BiasAt(t));
    for (int a = 0; a < 3; ++a) out[a][i] = y[a];
  }
  const std::vector<std::string> out_names =
      FamilyColumns(ColumnSensorKind(sensor), &OutputUnit(sensor));
  for (int a = 0; a < 3; ++a) {
    SetColumn(tag, out_names[static_cast<size_t>(a)], c.model.output_unit, std::move(out[a]));
  }
  if (temp != nullptr) *count = tc;
  return Status::Ok();
}

std::string Degc(double t) { return fmt::format("{:.2f}", t); }

// The temperature term M_c b1 (t - t_ref_c) at t, largest axis, in mg (accelerometer) or deg/s.
std::string TermAt(const SensorCalibration& c, double t_c) {
  const Eigen::Vector3d term = c.M() * (c.model.bias_per_c * (t_c - c.model.t_ref_c));
  const double largest = term.cwiseAbs().maxCoeff();
  if (c.model.sensor == ImuSensor::kAccel) return fmt::format("{:.1f} mg", 1000.0 * largest);
  return fmt::format("{:.2f} deg/s", largest);
}

}  // namespace

std::string FormatCalibrationReport(const Calibration& cal) {
  std::string out;
  // One record per line: the strings are calibration.json's data (escaped).
  const auto text = [](const std::string& data) { return EscapeControlChars(data); };
  out += fmt::format("calibration ({}), {}, {}\n", kCalibrationSchema, text(cal.tool_version),
                     text(cal.date_utc));
  out += fmt::format("gravity {} m/s^2\n", cal.gravity_mps2);
  // Constants marked model_rejected first, where no one scrolls past them (issue #36).
  const std::vector<std::string> rejected = ModelRejectedConstants(cal);
  if (!rejected.empty()) {
    out +=
        "MODEL_REJECTED: these constants are not certified; calibrate blob, push and the "
        "certificate refuse them unless --accept-rejected-model:\n";
    for (const std::string& r : rejected) out += "  " + r + "\n";
  }
  for (const InputFile& f : cal.inputs) {
    out += fmt::format("input {} sha256 {}\n", text(f.path), text(f.sha256));
  }
  for (const TagCalibration& t : cal.tags) {
    out += fmt::format("sensor {}: static detector factor {}, {} saturated samples excluded\n",
                       t.sensor, t.threshold_factor, t.saturated_samples);
    if (t.accel) ReportSensor(*t.accel, &out);
    if (t.gyro) ReportSensor(*t.gyro, &out);
    for (const std::string& w : t.warnings) out += "  warning: " + text(w) + "\n";
  }
  return out;
}

bool ValidityOptions::IsValid(std::string* why) const {
  const auto fail = [&](std::string msg) {
    if (why != nullptr) *why = std::move(msg);
    return false;
  };
  for (const auto& [end, name] :
       {std::pair{t_valid_min_c, "t_valid_min_c"}, std::pair{t_valid_max_c, "t_valid_max_c"}}) {
    if (end && !(*end >= kOperatingMinC && *end <= kOperatingMaxC)) {
      return fail(
          fmt::format("{} {} degC is outside the MPU6050 operating range; expected {} .. {}", name,
                      *end, kOperatingMinC, kOperatingMaxC));
    }
  }
  if (t_valid_min_c && t_valid_max_c) {
    if (!(*t_valid_min_c < *t_valid_max_c)) {
      return fail(fmt::format(
          "the temperature validity range {} .. {} degC must satisfy -40 <= min < max <= 85",
          *t_valid_min_c, *t_valid_max_c));
    }
    if (*t_valid_max_c - *t_valid_min_c < kMinValiditySpanC) {
      return fail(fmt::format(
          "the temperature validity range {} .. {} degC is {:.3g} degC wide; expected at least {} "
          "degC (twice the +-1 degC linearity of the MPU6050 temperature sensor)",
          *t_valid_min_c, *t_valid_max_c, *t_valid_max_c - *t_valid_min_c, kMinValiditySpanC));
    }
  }
  return true;
}

double TemperatureValidity::Clamp(double temp_c, double t_ref_c) const {
  const double t = std::isnan(temp_c) ? t_ref_c : temp_c;
  return std::clamp(t, min_c, max_c);
}

std::string TemperatureValidity::Describe() const {
  std::string from;
  if (span) {
    from = fmt::format("the static poses' span {} .. {} degC + {} degC", Degc(span->min_c),
                       Degc(span->max_c), kValidityMarginC);
  } else {
    from = "the MPU6050 operating range: no temperature span recorded";
  }
  if (explicit_min && explicit_max) return "as given; the default is " + from;
  if (explicit_min || explicit_max) {
    return fmt::format("{} as given, the other end from {}", explicit_min ? "minimum" : "maximum",
                       from);
  }
  return "from " + from;
}

Result<TemperatureValidity> TemperatureValidityRange(const SensorCalibration& c,
                                                     const ValidityOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const char* name = ImuSensorName(c.model.sensor);
  TemperatureValidity v;
  v.span = c.static_pose_temperature;
  if (v.span) {
    v.default_min_c = std::max(kOperatingMinC, v.span->min_c - kValidityMarginC);
    v.default_max_c = std::min(kOperatingMaxC, v.span->max_c + kValidityMarginC);
  }
  v.explicit_min = options.t_valid_min_c.has_value();
  v.explicit_max = options.t_valid_max_c.has_value();
  v.min_c = options.t_valid_min_c.value_or(v.default_min_c);
  v.max_c = options.t_valid_max_c.value_or(v.default_max_c);
  if (!(v.min_c < v.max_c && v.max_c - v.min_c >= kMinValiditySpanC)) {
    return MakeError(fmt::format(
        "{}: the temperature validity range {} .. {} degC ({}) is not a range of at least {} "
        "degC within {} .. {} degC; expected t_valid_min_c + {} <= t_valid_max_c",
        name, Degc(v.min_c), Degc(v.max_c), v.Describe(), kMinValiditySpanC, kOperatingMinC,
        kOperatingMaxC, kMinValiditySpanC));
  }
  const bool term = c.model.has_temperature;
  if (!v.span) {
    const std::string range = fmt::format("{} .. {} degC", Degc(v.min_c), Degc(v.max_c));
    if (term) {
      v.warnings.push_back(fmt::format(
          "{}: calibration.json records no static_pose_temperature, so the span the temperature "
          "term was fitted on is unknown; the validity range is {} ({}), where the term may be "
          "extrapolated (refit with temp_c to record the span, or give --t-valid-min-c and "
          "--t-valid-max-c)",
          name, range, v.Describe()));
    } else if (!(v.explicit_min && v.explicit_max)) {
      v.warnings.push_back(fmt::format(
          "{}: no temperature of the static poses recorded (no temp_c in the calibration data): "
          "the validity range is the MPU6050 operating range {}; the calibration has no "
          "temperature term, so the tag applies the same bias at every temperature",
          name, range));
    }
    return v;
  }
  const bool below = v.min_c<v.default_min_c, above = v.max_c> v.default_max_c;
  if (below || above) {
    std::string at;
    if (term) {
      std::vector<std::string> ends;
      if (below) ends.push_back(fmt::format("{} at {} degC", TermAt(c, v.min_c), Degc(v.min_c)));
      if (above) ends.push_back(fmt::format("{} at {} degC", TermAt(c, v.max_c), Degc(v.max_c)));
      at = fmt::format(
          "; the temperature term is extrapolated there: the tag applies {} (largest axis, 0 at "
          "t_ref_c {} degC)",
          fmt::join(ends, " and "), Degc(c.model.t_ref_c));
    } else {
      at = "; the calibration has no temperature term: its bias was measured at the fitted span "
           "only";
    }
    v.warnings.push_back(fmt::format(
        "{}: the validity range {} .. {} degC reaches beyond the fitted span {} .. {} degC plus "
        "the {} degC margin ({} .. {} degC){}",
        name, Degc(v.min_c), Degc(v.max_c), Degc(v.span->min_c), Degc(v.span->max_c),
        kValidityMarginC, Degc(v.default_min_c), Degc(v.default_max_c), at));
  }
  return v;
}

std::string SensorTemperatureCount::Describe() const {
  const std::string who = fmt::format("sensor {} {}", sensor, ImuSensorName(imu));
  const std::string range =
      fmt::format("the validity range {} .. {} degC", Degc(validity.min_c), Degc(validity.max_c));
  std::string line;
  if (outside() == 0) {
    line = fmt::format("{}: all {} samples with a temperature within {} ({})", who,
                       samples - missing, range, validity.Describe());
  } else {
    line = fmt::format("{}: {} of {} samples outside {} ({} below, {} above; {})", who, outside(),
                       samples, range, below, above, validity.Describe());
    line += temperature_term ? ": their temperature clamped to the range, as the tag does"
                             : ": the calibration has no temperature term, so the same bias "
                               "applies; it was measured within the range's span only";
  }
  if (missing > 0) {
    line += fmt::format(
        "; {} samples without a temperature (NaN temp_c){}", missing,
        temperature_term ? fmt::format(": t_ref_c {} degC applied, as the tag does", Degc(t_ref_c))
                         : "");
  }
  return line;
}

Result<ApplySummary> ApplyCalibration(const Calibration& calibration, Session* session,
                                      const ApplyCalibrationOptions& options) {
  METRO_CHECK(session != nullptr);
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  ApplySummary summary;
  for (Tag& tag : session->tags) {
    const TagCalibration* tc = calibration.FindTag(tag.sensor);
    if (tc == nullptr) {
      std::string have;
      for (const TagCalibration& t : calibration.tags) {
        have += (have.empty() ? "" : ", ") + std::to_string(t.sensor);
      }
      return MakeError(session->path, 0,
                       fmt::format("sensor {} has no calibration (the calibration file has "
                                   "sensors {})",
                                   tag.sensor, have));
    }
    for (const std::optional<SensorCalibration>* c : {&tc->accel, &tc->gyro}) {
      if (!*c) continue;
      Result<TemperatureValidity> validity = TemperatureValidityRange(**c, options.validity);
      if (!validity.ok()) {
        return MakeError(session->path, 0,
                         fmt::format("sensor {} {}", tag.sensor, validity.error().message));
      }
      for (const std::string& w : validity.value().warnings) {
        summary.warnings.push_back(fmt::format("sensor {} {}", tag.sensor, w));
      }
      std::optional<SensorTemperatureCount> count;
      Status s = ApplySensor(**c, validity.value(), *session, &tag, &count);
      if (!s.ok()) return s.error();
      if (count) summary.temperature.push_back(*count);
    }
    ++summary.tags_calibrated;
    summary.rows += static_cast<int64_t>(tag.size());
  }
  return summary;
}

SessionFormat CalibrationRecordsFormat(const Calibration& cal) {
  SessionFormat records = SessionFormat::kCsv;
  for (size_t i = 0; i < cal.inputs.size(); ++i) {
    SessionFormat f = SessionFormat::kCsv;
    if (!ParseSessionFormat(cal.inputs[i].format, &f) || IsThesisTagFormat(f)) {
      return SessionFormat::kCsv;
    }
    if (i == 0) records = f;
  }
  return records;
}

void NameFittedTags(const TagRegistry& tags, Calibration* cal) {
  const bool thesis_records = IsThesisTagFormat(CalibrationRecordsFormat(*cal));
  for (TagCalibration& t : cal->tags) {
    const TagEntry* entry = tags.Find(t.sensor);
    if (entry == nullptr) continue;
    t.device_id = entry->device_id;
    if (thesis_records || !entry->thesis_default) t.name = entry->name;
    t.profile = entry->profile;
  }
}

}  // namespace metro
