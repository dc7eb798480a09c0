// RenderCalibrationCertificate fills the "certificate" template in these stages, in order:
//
//   check       CheckCertifiable                model_rejected constants need a view or
//                                               --accept-rejected-model
//   identity    SetIdentity, InputRows,         certificate id, items, dates, inputs, the
//               SetSessionsNote, Traceability   records' note, traceability
//   tags        SetTags, AddConditions,         per tag: results (SensorData), conditions,
//               SensorData                      notes, warnings, coverage factors
//   validity    Validity, SetConformity         where the results apply; conformity
#include "metro/report/certificate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>

#include "html_templates.hpp"
#include "metro/calibration/calibration_io.hpp"
#include "metro/calibration/gravity_u.hpp"
#include "metro/core/device_id.hpp"
#include "metro/core/rounding.hpp"
#include "metro/core/utc_time.hpp"
#include "metro/report/svg_plot.hpp"
#include "metro/uncertainty/gum.hpp"

namespace metro {

namespace mustache = kainjow::mustache;

namespace {

std::string Short(double x, int digits) { return fmt::format("{:.{}g}", x, digits); }

// One row of the results table: value, u and U = k u, rounded per JCGM 100:2008 7.2.6.
mustache::data ResultRow(const std::string& constant, const std::string& unit, double value,
                         double u, double k) {
  mustache::data row;
  row.set("constant", constant);
  row.set("unit", unit);
  if (u > 0.0 && std::isfinite(u) && !(k > 0.0)) {
    // No coverage factor (dof < 1): u is stated, U is not.
    row.set("value", RoundForStatement(value, u).value);
    row.set("u", RoundForStatement(value, u).uncertainty);
    row.set("U", "not stated");
  } else if (u > 0.0 && std::isfinite(u)) {
    const RoundedResult expanded = RoundForStatement(value, k * u);  // JCGM 100:2008 6.2.1
    row.set("value", expanded.value);
    row.set("u", RoundForStatement(value, u).uncertainty);
    row.set("U", expanded.uncertainty);
  } else {
    row.set("value", Short(value, 8));
    row.set("u", "held");
    row.set("U", "held");
  }
  return row;
}

const char* kAxes[3] = {"x", "y", "z"};

// The coverage factor of one sensor's U and the dof it was taken at: k = t_{(1+p)/2}(nu),
// nu = the fit's dof (JCGM 100:2008 G.3.2); nu is infinite, k the normal quantile, when the
// file's coverage_factor_95 is the normal 1.96 (an accelerometer u from the poses' noise
// alone, G.6.6). k = 0 when dof < 1 (no U can be stated).
struct Coverage {
  double k = 0.0;
  double dof = 0.0;  // +infinity: the normal quantile.
  std::string text;  // "k = t_0.975(12) = 2.18 (12 degrees of freedom ...)".
};
Coverage SensorCoverage(const SensorCalibration& c, double p) {
  Coverage out;
  const double z975 = CoverageFactor(0.95, std::numeric_limits<double>::infinity());
  const std::string q = Short(0.5 * (1.0 + p), 4);
  // u rests on the poses' noise alone only when the residuals agree with that noise: with a
  // reduced chi-square above the 99 % point of its law at the fit's dof the noise does not
  // explain the scatter, and k is Student's t at that dof (issue #36).
  const bool noise_agrees =
      c.dof >= 1 &&
      c.reduced_chi2 * c.dof <=
          boost::math::quantile(boost::math::chi_squared(static_cast<double>(c.dof)), 0.99);
  if (c.dof >= 1 && std::abs(c.coverage_factor_95 - z975) < 1e-9 && noise_agrees) {
    out.dof = std::numeric_limits<double>::infinity();
    out.k = CoverageFactor(p, out.dof);
    out.text = fmt::format(
        "k = t_{}(inf) = {}: the uncertainty rests on the poses' noise (hundreds of samples "
        "each), so its degrees of freedom are taken as infinite (JCGM 100:2008 G.6.6); the "
        "residuals agree with that noise (reduced chi-square {} at the fit's {} dof)",
        q, Short(out.k, 4), Short(c.reduced_chi2, 3), c.dof);
  } else if (c.dof >= 1) {
    out.dof = c.dof;
    out.k = CoverageFactor(p, out.dof);
    out.text = fmt::format(
        "k = t_{}({}) = {} (Student's t at the fit's {} degrees of freedom, JCGM 100:2008 "
        "G.3.2){}",
        q, c.dof, Short(out.k, 4), c.dof,
        std::abs(c.coverage_factor_95 - z975) < 1e-9
            ? fmt::format("; the residuals are {} times the poses' noise (reduced chi-square "
                          "{}), so u does not rest on that noise alone",
                          Short(std::sqrt(c.reduced_chi2), 3), Short(c.reduced_chi2, 3))
            : std::string());
  } else {
    out.text = fmt::format(
        "no coverage factor: the fit has {} degrees of freedom (fewer than 1), so only u is stated",
        c.dof);
  }
  return out;
}

// Section 6, the statement of conformity with its decision rule (ISO/IEC 17025:2017 7.8.6.2),
// when calibration.json carries one (docs/conformity.md).
void SetConformity(const Calibration& cal, mustache::data* data) {
  if (!cal.conformity) return;
  const ConformityStatement& st = *cal.conformity;
  const double k = st.coverage_factor;
  mustache::data rows{mustache::data::type::list};
  int pass = 0, fail = 0, inconclusive = 0;
  auto limit = [](const std::optional<double>& v) { return v ? Short(*v, 8) : std::string("-"); };
  for (const ConformityEntry& e : st.entries) {
    mustache::data row = ResultRow(e.constant, e.unit, e.value, e.u, k);
    row.set("sensor", std::to_string(e.sensor));
    row.set("lower", limit(e.lower));
    row.set("upper", limit(e.upper));
    row.set("acceptance", e.acceptance_lower || e.acceptance_upper
                              ? limit(e.acceptance_lower) + " .. " + limit(e.acceptance_upper)
                              : std::string("p_c rule"));
    row.set("p_c", fmt::format("{:.4f}", e.p_conformance));
    row.set("decision", ConformityDecisionName(e.decision));
    rows.push_back(row);
    (e.decision == ConformityDecision::kPass   ? pass
     : e.decision == ConformityDecision::kFail ? fail
                                               : inconclusive) += 1;
  }
  mustache::data c;
  c.set("rule", st.DescribeRule());
  c.set("k", Short(k, 3));
  c.set("rows", rows);
  c.set("summary", fmt::format("{} of {} constants pass, {} fail, {} inconclusive.", pass,
                               st.entries.size(), fail, inconclusive));
  c.set("all_pass", fail == 0 && inconclusive == 0 ? mustache::data(true) : mustache::data(false));
  data->set("conformity", c);
}

// The static residuals before and after calibration that the fit recorded.
Result<std::string> ResidualPlot(const StaticResiduals& r, bool accel) {
  PlotSeries before, after;
  before.label = "before (nominal sensitivity)";
  before.style = SeriesStyle::kPoints;
  before.color = PlotColor::kOrange;
  after.label = "after calibration";
  after.style = SeriesStyle::kPoints;
  after.color = PlotColor::kBlue;
  // |residual| on a logarithmic axis: after calibration the residuals are orders of magnitude
  // smaller than before, and a linear axis would draw them on zero. An exact zero has no
  // logarithm and is left out.
  for (size_t i = 0; i < r.before.size() && i < r.after.size(); ++i) {
    const double x = static_cast<double>(i + 1);
    const double b = std::abs(r.before[i]), a = std::abs(r.after[i]);
    if (b > 0.0 && std::isfinite(b)) {
      before.x.push_back(x);
      before.y.push_back(b);
    }
    if (a > 0.0 && std::isfinite(a)) {
      after.x.push_back(x);
      after.y.push_back(a);
    }
  }
  XyPlot plot;
  plot.title = accel ? "Accelerometer: gravity-norm error per static pose"
                     : "Gyroscope: rate magnitude per static interval";
  plot.x_label = "static pose";
  plot.y_label = accel ? "||a| - g_local/g_n| [g], log scale" : "|w| [deg/s], log scale";
  plot.log_y = true;
  plot.series = {std::move(before), std::move(after)};
  return RenderXyPlot(plot);
}

// What the page says where calibration.json lacks what the fit now records from the data.
constexpr const char* kRefit =
    "re-run `calibrate fit` on the input records to get them (docs/calibration-format.md)";

// The model check of a sensor (issue #36): the comparisons and the chosen model's standing.
void SetModelCheck(const SensorCalibration& c, const CertificateOptions& options,
                   mustache::data* d) {
  if (!c.model_check) return;
  const ModelCheck& mc = *c.model_check;
  mustache::data check;
  std::string line = fmt::format("Model '{}' ({}): {}", ModelKindName(c.model.kind),
                                 mc.selection == "auto" ? "chosen by --model auto, the smallest "
                                                          "model of bias < scale < full the data "
                                                          "accept"
                                                        : "as given",
                                 mc.status);
  if (mc.chi2 >= 0) {
    line += fmt::format("; residuals against the noise: chi-square {} over {} dof",
                        Short(mc.chi2, 4), Short(mc.chi2_dof, 4));
    if (mc.p_value >= 0) line += fmt::format(", p = {}", Short(mc.p_value, 3));
  }
  check.set("line", line + ".");
  mustache::data rows{mustache::data::type::list};
  for (const ModelComparison& cmp : mc.comparisons) {
    mustache::data row;
    row.set("pair", fmt::format("{} vs {}", ModelKindName(cmp.smaller), ModelKindName(cmp.larger)));
    if (cmp.test.empty()) {
      row.set("test", "-");
      row.set("statistic", "-");
      row.set("dof", "-");
      row.set("p", "-");
      row.set("decision", cmp.note);
    } else {
      row.set("test", cmp.test == "F" ? "F" : "chi-square difference");
      row.set("statistic", Short(cmp.statistic, 4));
      row.set("dof", cmp.test == "F" ? fmt::format("{}, {}", Short(cmp.dof1, 3), Short(cmp.dof2, 4))
                                     : Short(cmp.dof1, 3));
      row.set("p", cmp.p_value < 1e-16 ? std::string("< 1e-16") : Short(cmp.p_value, 3));
      row.set("decision", fmt::format("{} {}", cmp.rejected ? "rejects" : "accepts",
                                      ModelKindName(cmp.smaller)));
    }
    rows.push_back(row);
  }
  check.set("comparisons", rows);
  check.set("has_comparisons", !mc.comparisons.empty());
  if (mc.type_b) {
    std::string terms;
    for (const std::string& t : mc.type_b->terms) terms += (terms.empty() ? "" : ", ") + t;
    check.set("type_b",
              fmt::format("u includes a Type B term for the cross-axis sensitivity the model "
                          "leaves out: {} each +-{} rad, {} (u = {} rad), from {}; propagated to "
                          "every constant through the fit's Jacobian (JCGM 100:2008 5.1.2).",
                          terms, Short(mc.type_b->half_width, 3), mc.type_b->distribution,
                          Short(mc.type_b->u, 3), mc.type_b->source));
  }
  if (!mc.reason.empty() && mc.status != "accepted") check.set("reason", mc.reason);
  if (mc.model_rejected && options.accept_rejected_model) {
    check.set("rejected",
              "These constants are marked model_rejected and are stated only because "
              "--accept-rejected-model was given: their U does not cover what the model leaves "
              "out.");
  } else if (mc.model_rejected) {
    check.set("rejected",
              "These constants are marked model_rejected and are not certified: this page is a "
              "view of calibration.json; their U does not cover what the model leaves out, and "
              "calibrate blob, calibrate push and the certificate refuse them unless "
              "--accept-rejected-model.");
  }
  d->set("model_check", check);
}

// The view's banner (CertificateOptions::view): each sensor whose constants are marked
// model_rejected, with its model, status and reason.
mustache::data RejectedBanner(const Calibration& cal) {
  mustache::data banner;
  mustache::data rows{mustache::data::type::list};
  for (const TagCalibration& t : cal.tags) {
    for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
      if (!c->has_value() || !(*c)->model_check || !(*c)->model_check->model_rejected) continue;
      const ModelCheck& mc = *(*c)->model_check;
      mustache::data row;
      row.set("sensor",
              fmt::format("sensor {} {}", t.sensor, ImuSensorLongName((*c)->model.sensor)));
      row.set("model", fmt::format("'{}' model, {}", ModelKindName((*c)->model.kind), mc.status));
      row.set("reason", mc.reason);
      rows.push_back(row);
    }
  }
  banner.set("rows", rows);
  return banner;
}

mustache::data SensorData(const SensorCalibration& c, int sensor, const GravityUncertainty& gravity,
                          double gravity_mps2, const CertificateOptions& options) {
  const SensorModel& m = c.model;
  const Coverage coverage = SensorCoverage(c, options.coverage_probability);
  const double k = coverage.k;
  const bool accel = m.sensor == ImuSensor::kAccel;
  mustache::data d;
  d.set("sensor", std::to_string(sensor));
  d.set("title", ImuSensorLongName(m.sensor));
  d.set("model", ModelKindName(m.kind));
  d.set("input_unit", m.input_unit);
  d.set("output_unit", m.output_unit);
  d.set("dof", std::to_string(c.dof));
  d.set("chi2", Short(c.reduced_chi2, 4));
  d.set("k", k > 0.0 ? Short(k, 4) : std::string("-"));
  d.set("coverage", coverage.text);
  mustache::data rows{mustache::data::type::list};
  for (int a = 0; a < 3; ++a) {
    rows.push_back(
        ResultRow(fmt::format("bias b0_{}", kAxes[a]), m.input_unit, m.bias[a], c.bias_u[a], k));
  }
  // The accelerometer's scale factors and sensitivities with the gravity value's relative
  // uncertainty (GravityUncertainty): u_c^2 = u^2 + (x u(g) / g)^2, JCGM 100:2008 5.1.2.
  const double rel_g = accel ? gravity.u_mps2 / gravity_mps2 : 0.0;
  const auto with_g = [rel_g](double x, double u) {
    return u > 0.0 ? std::hypot(u, x * rel_g) : u;
  };
  const std::string scale_unit = fmt::format("{}/{}", m.output_unit, m.input_unit);
  for (int a = 0; a < 3; ++a) {
    rows.push_back(ResultRow(fmt::format("scale k_{}", kAxes[a]), scale_unit, m.scale[a],
                             with_g(m.scale[a], c.scale_u[a]), k));
  }
  static const char* kAccelTerms[3] = {"a_yz", "a_zy", "a_zx"};
  static const char* kGyroTerms[6] = {"g_yz", "g_zy", "g_xz", "g_zx", "g_xy", "g_yx"};
  for (int i = 0; i < MisalignmentCount(m.sensor); ++i) {
    const double v = static_cast<size_t>(i) < m.misalignment.size() ? m.misalignment[i] : 0.0;
    const double u = static_cast<size_t>(i) < c.misalignment_u.size() ? c.misalignment_u[i] : 0.0;
    rows.push_back(ResultRow(fmt::format("misalignment {}", accel ? kAccelTerms[i] : kGyroTerms[i]),
                             "rad", v, u, k));
  }
  if (m.has_temperature) {
    for (int a = 0; a < 3; ++a) {
      rows.push_back(ResultRow(
          fmt::format("bias temperature b1_{} (t_ref = {:.2f} degC)", kAxes[a], m.t_ref_c),
          m.input_unit + "/degC", m.bias_per_c[a], c.bias_per_c_u[a], k));
    }
  }
  for (int a = 0; a < 3; ++a) {
    rows.push_back(ResultRow(fmt::format("sensitivity 1/k_{}", kAxes[a]),
                             fmt::format("{}/{}", m.input_unit, m.output_unit), c.sensitivity[a],
                             with_g(c.sensitivity[a], c.sensitivity_u[a]), k));
  }
  d.set("rows", rows);
  if (accel) {
    d.set("gravity_budget",
          fmt::format("Gravity value: {}. Its relative uncertainty {} % is included in u and U of "
                      "the scale factors and sensitivities (the fit's target norm g / g_n scales "
                      "M and leaves the biases and misalignment terms unchanged); "
                      "calibration.json states them as scale_u_with_gravity and "
                      "sensitivity_u_with_gravity beside its gravity_uncertainty, its "
                      "covariance is the fit's alone.",
                      gravity.statement, Short(100.0 * rel_g, 3)));
  }
  SetModelCheck(c, options, &d);
  mustache::data groups{mustache::data::type::list};
  for (const ResidualGroup& g : c.groups) {
    mustache::data row;
    row.set("kind", g.kind);
    row.set("count", std::to_string(g.count));
    row.set("rms", Short(g.rms, 3));
    row.set("unit", g.unit);
    groups.push_back(row);
  }
  d.set("groups", groups);
  mustache::data plots{mustache::data::type::list};
  mustache::data f;
  if (!c.static_residuals) {
    f.set("svg", "");
    f.set("caption", fmt::format("Residuals before/after calibration: not in this calibration.json "
                                 "(written before metro recorded them at fit time); {}.",
                                 kRefit));
  } else if (c.static_residuals->before.empty()) {
    f.set("svg", "");
    f.set("caption",
          "Residuals before/after calibration: not drawn (the fit used no static "
          "segment).");
  } else if (Result<std::string> svg = ResidualPlot(*c.static_residuals, accel); !svg.ok()) {
    f.set("svg", "");
    f.set("caption",
          "Residuals before/after calibration: not drawn (" + svg.error().message + ").");
  } else {
    f.set("svg", svg.value());
    f.set("caption",
          fmt::format("Absolute residual of each of the {} static segments the fit used, on a "
                      "logarithmic axis: before calibration (raw means at the nominal "
                      "sensitivity{}) and after (the calibrated model); computed by the fit.",
                      c.static_residuals->before.size(),
                      m.input_unit == "LSB" && c.full_scale
                          ? fmt::format(", +-{} {} range", Short(*c.full_scale, 6),
                                        OutputUnit(m.sensor).symbol)
                          : ""));
  }
  plots.push_back(f);
  d.set("plots", plots);
  return d;
}

// ---- Identification (ISO/IEC 17025:2017 7.8.2.1) from calibration.json alone --------------

// What the records' format says about the item.
std::string FormatSource(const std::string& format) {
  if (format.empty()) return "format not recorded in calibration.json";
  if (format == "receiver") {
    return "receiver capture (the nRF52840 central's hex lines of metro BLE tags)";
  }
  if (format == "imutk") return "imu_tk accelerometer + gyroscope file pair";
  if (format == "csv") return "session.csv";
  return fmt::format("{} file", format);
}

// The IMU as far as the data and the tags file say: the declared profile, the receiver format
// (which carries only metro's MPU6050 tags), or "not declared". Never a guess.
std::string ImuDescription(const TagCalibration& t, const std::vector<std::string>& formats) {
  if (t.profile == "mpu6050")
    return "InvenSense MPU6050 (profile mpu6050 declared in the tags file)";
  if (t.profile == "generic") {
    return "IMU type not specified (profile generic declared in the tags file)";
  }
  if (!t.profile.empty()) return fmt::format("profile {} (tags file)", t.profile);
  if (!formats.empty() && std::all_of(formats.begin(), formats.end(),
                                      [](const std::string& f) { return f == "receiver"; })) {
    return "MPU6050 on an nRF51802 BLE tag (receiver capture; no profile declared)";
  }
  return "IMU type not declared (no profile in a tags file)";
}

std::string SensorInput(const SensorCalibration& c) {
  const bool accel = c.model.sensor == ImuSensor::kAccel;
  std::string range;
  if (c.model.input_unit == "LSB") {
    range = c.full_scale
                ? fmt::format(", raw counts; the fit's nominal sensitivity at +-{} {} full scale",
                              Short(*c.full_scale, 6), accel ? "g" : "deg/s")
                : std::string(
                      ", raw counts; full-scale setting not recorded in "
                      "calibration.json");
  }
  return fmt::format("{} (input {}{})", accel ? "accelerometer" : "gyroscope", c.model.input_unit,
                     range);
}

mustache::data ItemRows(const Calibration& cal) {
  mustache::data rows{mustache::data::type::list};
  for (const TagCalibration& t : cal.tags) {
    // The inputs this tag's segments came from (all inputs when none is recorded).
    std::vector<std::string> formats;
    for (size_t i = 0; i < cal.inputs.size(); ++i) {
      const bool used = t.segments.empty() ||
                        std::any_of(t.segments.begin(), t.segments.end(), [i](const Segment& s) {
                          return s.piece == static_cast<int>(i);
                        });
      if (used &&
          std::find(formats.begin(), formats.end(), cal.inputs[i].format) == formats.end()) {
        formats.push_back(cal.inputs[i].format);
      }
    }
    std::string sources;
    for (const std::string& f : formats) sources += (sources.empty() ? "" : "; ") + FormatSource(f);
    std::string sensors;
    for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
      if (c->has_value()) sensors += (sensors.empty() ? "" : " and ") + SensorInput(**c);
    }
    mustache::data row;
    row.set("sensor", std::to_string(t.sensor));
    row.set("name", t.name.empty() ? std::string("not stated") : t.name);
    row.set("device_id",
            t.device_id ? FormatDeviceIdText(*t.device_id) : std::string("not stated"));
    if (t.device_id)
      row.set("device_id_words", "nrfjprog order " + FormatDeviceIdWords(*t.device_id));
    row.set("imu", ImuDescription(t, formats));
    row.set("sensors", sensors);
    row.set("source", sources.empty() ? std::string("no input recorded") : sources);
    rows.push_back(row);
  }
  return rows;
}

// Dates of measurement (7.8.2.1 f), distinct from the fit's and the date.
std::string MeasurementDates(const Calibration& cal) {
  std::string first, last;
  int dated = 0, relative = 0, unrecorded = 0;
  for (const InputFile& in : cal.inputs) {
    if (!in.start_utc.empty()) {
      ++dated;
      if (first.empty() || in.start_utc < first) first = in.start_utc;
      if (last.empty() || in.end_utc > last) last = in.end_utc;
    } else if (in.duration_s) {
      ++relative;
    } else {
      ++unrecorded;
    }
  }
  std::string out;
  if (dated > 0) out = fmt::format("{} .. {} (UTC, from the records' time columns)", first, last);
  if (relative > 0) {
    out += fmt::format(
        "{}{} record(s) with relative times only (a clock since the start, no date): measured on "
        "or before the fit, {}",
        out.empty() ? "" : "; ", relative, cal.date_utc);
  }
  if (unrecorded > 0) {
    out += fmt::format(
        "{}{} record(s) whose time span calibration.json does not record (written before metro "
        "recorded it): measured on or before the fit, {}",
        out.empty() ? "" : "; ", unrecorded, cal.date_utc);
  }
  return out.empty() ? std::string("no input recorded") : out;
}

std::string GravityStatement(const Calibration& cal) {
  const std::string g = Short(cal.gravity_mps2, 8);
  if (cal.gravity_source == "given") {
    return fmt::format("{} m/s^2, given: calibrate fit --gravity-mps2 {}", g, g);
  }
  if (cal.gravity_source == "standard") {
    return fmt::format(
        "{} m/s^2, standard gravity g_n (conventional value, 3rd CGPM 1901), not a measured local "
        "gravity",
        g);
  }
  return fmt::format("{} m/s^2 (source not recorded in calibration.json)", g);
}

// Metrological traceability (7.8.4.1 c, 6.5): what the constants rest on, as recorded.
std::vector<std::string> Traceability(const Calibration& cal) {
  std::vector<std::string> out;
  bool accel = false, table = false, rotation = false, gyro = false;
  for (const TagCalibration& t : cal.tags) {
    accel = accel || t.accel.has_value();
    if (t.gyro) {
      gyro = true;
      for (const ResidualGroup& g : t.gyro->groups) {
        table = table || (g.kind == "table_rate" && g.count > 0);
        rotation = rotation || (g.kind == "rotation_gravity" && g.count > 0);
      }
    }
  }
  const std::string g = Short(cal.gravity_mps2, 8) + " m/s^2";
  if (accel) {
    out.push_back(
        cal.gravity_source == "given"
            ? fmt::format(
                  "Accelerometer: traceable only to the gravity value {} given by the user; "
                  "its own traceability and uncertainty are not recorded and not in U.",
                  g)
        : cal.gravity_source == "standard"
            ? fmt::format("Accelerometer: referred to standard gravity {}, a conventional value, "
                          "not to a measurement of local gravity (which differs from it by up to "
                          "0.3 %, 9.78 .. 9.83 m/s^2); that difference is not in U.",
                          g)
            : fmt::format("Accelerometer: referred to the gravity value {}, whose source "
                          "calibration.json does not record.",
                          g));
  }
  if (gyro) {
    std::string refs =
        "the gyroscope bias to rest (zero rate; the Earth's rotation, 0.0042 deg/s, "
        "is not corrected)";
    if (table) {
      refs +=
          "; its scale to the rotation-table rates recorded in the records (table_rate_dps), "
          "whose calibration is not recorded";
    }
    if (rotation) {
      refs +=
          "; its scale and misalignment to the angle between the gravity directions of "
          "consecutive static poses (the accelerometer as reference)";
    }
    out.push_back("Gyroscope: " + refs + ".");
  }
  out.push_back(
      "No further link to the SI is claimed: no reference standard with its own calibration "
      "certificate took part, and the time base is the record's own clock.");
  return out;
}

// ---- RenderCalibrationCertificate's stages --------------------------------------------------

// Constants marked model_rejected are certified only with --accept-rejected-model (a view
// states them as not a certificate).
Status CheckCertifiable(const std::vector<std::string>& rejected, bool not_certificate,
                        const CertificateOptions& options) {
  if (not_certificate && !options.view) {
    std::string list;
    for (const std::string& r : rejected) list += (list.empty() ? "" : "; ") + r;
    return MakeError(fmt::format(
        "certificate: constants marked model_rejected cannot be certified: {}. Refit, or give "
        "--accept-rejected-model to state them with that notice",
        list));
  }
  return Status::Ok();
}

// Section 1: the certificate's identity, the items, the dates, the gravity value.
void SetIdentity(const Calibration& cal, const std::string& certificate_id, bool not_certificate,
                 mustache::data* data) {
  data->set("certificate_id",
            fmt::format("{} (first 16 hex digits of the SHA-256 of the calibration JSON)",
                        certificate_id));
  data->set("print_id", certificate_id);
  data->set("print_label",
            not_certificate ? "Calibration report (not a certificate)" : "Calibration certificate");
  data->set("id_label", not_certificate ? "calibration.json (not a certificate)" : "certificate");
  if (not_certificate) data->set("rejected_banner", RejectedBanner(cal));
  data->set("item_rows", ItemRows(cal));
  data->set("date_issue_utc", UtcIso8601Now());
  data->set("date_utc", cal.date_utc);
  data->set("measurement_dates", MeasurementDates(cal));
  data->set("tool_version", cal.tool_version);
  data->set("gravity", GravityStatement(cal));
}

// The input files, one row each.
mustache::data InputRows(const Calibration& cal) {
  mustache::data inputs{mustache::data::type::list};
  for (size_t i = 0; i < cal.inputs.size(); ++i) {
    const InputFile& in = cal.inputs[i];
    mustache::data row;
    row.set("index", std::to_string(i));
    row.set("path", in.path);
    row.set("sha256", in.sha256);
    row.set("format", in.format.empty() ? std::string("not recorded") : in.format);
    row.set("duration",
            in.duration_s ? fmt::format("{:.1f} s", *in.duration_s) : std::string("not recorded"));
    row.set("measured", !in.start_utc.empty() ? in.start_utc + " .. " + in.end_utc
                        : in.duration_s       ? std::string("relative times only")
                                              : std::string("not recorded"));
    inputs.push_back(row);
  }
  return inputs;
}

// What the fit recorded from the records: every tag's conditions and every sensor's
// residuals (true), or a calibration.json from before that.
bool SetSessionsNote(const Calibration& cal, mustache::data* data) {
  bool recorded = true;
  for (const TagCalibration& t : cal.tags) {
    recorded = recorded && t.record_conditions.has_value();
    for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
      recorded = recorded && (!c->has_value() || (*c)->static_residuals.has_value());
    }
  }
  data->set("sessions_ok", recorded);
  data->set("sessions_note",
            recorded ? std::string("Conditions and residual plots as computed from the input "
                                   "records by the fit (calibration.json's record_conditions and "
                                   "static_residuals).")
                     : fmt::format("This calibration.json was written before metro recorded the "
                                   "records' conditions and the static residuals at fit time: "
                                   "the temperature range of the records and the residual plots "
                                   "are not in it; {}.",
                                   kRefit));
  return recorded;
}

// The conditions of each record of tag t, as the fit recorded them, and the notes on its
// poses' temperatures and temperature terms.
void AddConditions(const Calibration& cal, const TagCalibration& t, mustache::data* conditions,
                   mustache::data* condition_notes) {
  for (const RecordConditions& r :
       t.record_conditions ? *t.record_conditions : std::vector<RecordConditions>{}) {
    mustache::data row;
    row.set("sensor", std::to_string(t.sensor));
    row.set("record", r.input >= 0 && static_cast<size_t>(r.input) < cal.inputs.size()
                          ? cal.inputs[static_cast<size_t>(r.input)].path
                          : fmt::format("input {}", r.input));
    row.set("samples", std::to_string(r.samples));
    row.set("duration", fmt::format("{:.1f} s", r.duration_s));
    row.set("temperature", r.temp_min_c && r.temp_max_c
                               ? fmt::format("{:.2f} .. {:.2f} degC", *r.temp_min_c, *r.temp_max_c)
                               : std::string("not recorded (no temp_c column)"));
    conditions->push_back(row);
  }
  // The static poses' temperatures, from calibration.json (also without the records).
  const std::optional<SensorCalibration>& first = t.accel ? t.accel : t.gyro;
  if (first && first->static_pose_temperature) {
    const PoseTemperatureRange& r = *first->static_pose_temperature;
    condition_notes->push_back(mustache::data(fmt::format(
        "sensor {}: the {} static poses were at {:.2f} .. {:.2f} degC (mean {:.2f} degC)", t.sensor,
        r.poses, r.min_c, r.max_c, r.mean_c)));
  }
  for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
    if (c->has_value() && (*c)->model.has_temperature) {
      condition_notes->push_back(mustache::data(
          fmt::format("sensor {} {}: linear temperature term fitted about t_ref = {:.2f} degC",
                      t.sensor, ImuSensorName((*c)->model.sensor), (*c)->model.t_ref_c)));
    }
  }
}

// Sections 3 and 4 for every tag: its sensors' results, conditions and warnings; returns the
// coverage factor of each sensor, in words, for the validity section.
std::vector<std::string> SetTags(const Calibration& cal, const GravityUncertainty& gravity,
                                 const CertificateOptions& options, bool recorded,
                                 mustache::data* data) {
  mustache::data tags{mustache::data::type::list};
  mustache::data conditions{mustache::data::type::list};
  mustache::data condition_notes{mustache::data::type::list};
  mustache::data warnings{mustache::data::type::list};
  std::vector<std::string> coverage_lines;
  for (const TagCalibration& t : cal.tags) {
    mustache::data td;
    td.set("sensor", std::to_string(t.sensor));
    mustache::data sensors{mustache::data::type::list};
    for (const std::optional<SensorCalibration>* c : {&t.accel, &t.gyro}) {
      if (!c->has_value()) continue;
      sensors.push_back(SensorData(**c, t.sensor, gravity, cal.gravity_mps2, options));
      const Coverage cov = SensorCoverage(**c, options.coverage_probability);
      coverage_lines.push_back(
          cov.k > 0.0
              ? fmt::format("sensor {} {}: k = {} at {} degrees of freedom", t.sensor,
                            ImuSensorName((*c)->model.sensor), Short(cov.k, 4),
                            std::isinf(cov.dof) ? std::string("infinite") : Short(cov.dof, 6))
              : fmt::format("sensor {} {}: no U (fewer than 1 degree of freedom)", t.sensor,
                            ImuSensorName((*c)->model.sensor)));
    }
    td.set("sensors", sensors);
    tags.push_back(td);
    for (const std::string& w : t.warnings) {
      warnings.push_back(mustache::data(fmt::format("sensor {}: {}", t.sensor, w)));
    }
    AddConditions(cal, t, &conditions, &condition_notes);
  }
  if (!recorded) {
    condition_notes.push_back(mustache::data(
        fmt::format("The temperature range of the records is not stated: this calibration.json "
                    "does not record it (written before metro recorded the records' conditions "
                    "at fit time); {}.",
                    kRefit)));
  }
  data->set("tags", tags);
  data->set("conditions", conditions);
  data->set("condition_notes", condition_notes);
  data->set("warnings", warnings);
  return coverage_lines;
}

// Section 5: where the results apply.
mustache::data Validity(const GravityUncertainty& gravity, const CertificateOptions& options,
                        const std::vector<std::string>& coverage_lines,
                        const std::vector<std::string>& rejected, bool not_certificate) {
  mustache::data validity{mustache::data::type::list};
  validity.push_back(mustache::data(
      "The results relate only to the tag(s) identified above, with the input units and "
      "full-scale settings of the records, and apply through the model of section 2."));
  validity.push_back(mustache::data(
      "They are valid within the temperature range of section 4; outside it (or away from "
      "t_ref without a temperature term) the biases may differ by more than U."));
  if (!coverage_lines.empty()) {
    std::string list;
    for (const std::string& l : coverage_lines) list += (list.empty() ? "" : "; ") + l;
    validity.push_back(mustache::data(fmt::format(
        "Each U = k u has a coverage probability of about {} % with k = t_{}(nu), Student's t "
        "at the degrees of freedom nu named with it (section 3; JCGM 100:2008 G.3.2, G.6.6): "
        "{}.",
        Short(100.0 * options.coverage_probability, 4),
        Short(0.5 * (1.0 + options.coverage_probability), 4), list)));
  }
  validity.push_back(mustache::data(fmt::format(
      "Uncertainties are Type A from the fit, plus the Type B terms section 3 names (the "
      "gravity value's for the accelerometer's scale factors: {}; the cross-axis terms a model "
      "leaves out); they do not include the table rate's uncertainty or long-term drift of the "
      "tag (traceability below).",
      gravity.statement)));
  for (const std::string& r : rejected) {
    validity.push_back(mustache::data(
        not_certificate
            ? "Not certified (marked model_rejected; this page is a view, not a "
              "certificate): " +
                  r
            : "Stated with --accept-rejected-model although marked model_rejected: " + r));
  }
  return validity;
}

}  // namespace

bool CertificateOptions::IsValid(std::string* why) const {
  if (!(coverage_probability > 0.0 && coverage_probability < 1.0)) {
    *why = fmt::format("certificate: coverage probability p = {} is outside (0, 1)",
                       coverage_probability);
    return false;
  }
  return true;
}

Result<std::string> RenderCalibrationCertificate(const Calibration& cal,
                                                 const CertificateOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return MakeError(why);
  const std::vector<std::string> rejected = ModelRejectedConstants(cal);
  const bool not_certificate = !rejected.empty() && !options.accept_rejected_model;
  if (Status s = CheckCertifiable(rejected, not_certificate, options); !s.ok()) return s.error();
  const GravityUncertainty gravity = GravityUncertaintyOf(cal);
  const std::string certificate_id =
      options.certificate_id.empty() ? CalibrationCertificateId(cal) : options.certificate_id;
  std::string items;  // For the page's subtitle.
  for (const TagCalibration& t : cal.tags) {
    items += fmt::format("{}sensor {}", items.empty() ? "" : ", ", t.sensor);
  }
  mustache::data data;
  SetIdentity(cal, certificate_id, not_certificate, &data);
  data.set("inputs", InputRows(cal));
  const bool recorded = SetSessionsNote(cal, &data);
  data.set("p", Short(100.0 * options.coverage_probability, 4));
  mustache::data traceability{mustache::data::type::list};
  for (const std::string& line : Traceability(cal)) traceability.push_back(mustache::data(line));
  data.set("traceability", traceability);
  const std::vector<std::string> coverage_lines = SetTags(cal, gravity, options, recorded, &data);
  data.set("validity", Validity(gravity, options, coverage_lines, rejected, not_certificate));
  SetConformity(cal, &data);

  Result<std::string> body = report_internal::RenderTemplate("certificate", std::move(data));
  if (!body.ok()) return body;
  return report_internal::RenderPage(
      not_certificate ? "Calibration report (not a certificate)" : "Calibration certificate",
      fmt::format("{} - {} - {} {}", kCalibrationSchema, items,
                  not_certificate ? "calibration.json" : "certificate", certificate_id),
      body.value());
}

}  // namespace metro
