// calibration.json's codec (docs/calibration-format.md): the writer keeps every key and
// number text metro has written; the reader checks each value at its own position
// (JsonCursor) and refuses redundant fields that disagree.
#include "calibration/calibration_json.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "core/json_text.hpp"
#include "metro/calibration/gravity_u.hpp"
#include "metro/core/device_id.hpp"
#include "metro/core/file.hpp"
#include "metro/core/utc_time.hpp"

namespace metro {

using nlohmann::json;

namespace {

json Vec(const Eigen::Vector3d& v) { return json::array({v[0], v[1], v[2]}); }

json Mat(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(row);
  }
  return rows;
}

json SegmentJson(const Segment& s) {
  json j = {{"kind", SegmentKindName(s.kind)},
            {"input", s.piece},
            {"begin_index", s.begin},
            {"end_index", s.end},
            {"start_s", s.start_s},
            {"end_s", s.end_s},
            {"used", s.used}};
  if (s.kind == SegmentKind::kTable) j["table_rate_dps"] = s.table_rate_dps;
  if (s.kind == SegmentKind::kStatic && s.pose >= 0) j["pose"] = s.pose + 1;
  if (s.kind == SegmentKind::kSteady && std::isfinite(s.steady_rate_dps)) {
    j["steady_rate_dps"] = s.steady_rate_dps;
  }
  if (!s.note.empty()) j["note"] = s.note;
  return j;
}

json ModelCheckJson(const ModelCheck& m) {
  json j;
  j["selection"] = m.selection;
  j["status"] = m.status;
  j["model_rejected"] = m.model_rejected;
  if (m.chi2 >= 0) {
    j["chi2"] = m.chi2;
    j["chi2_dof"] = m.chi2_dof;
  }
  if (m.p_value >= 0) j["p_value"] = m.p_value;
  if (!m.reason.empty()) j["reason"] = m.reason;
  json comparisons = json::array();
  for (const ModelComparison& c : m.comparisons) {
    json cj;
    cj["smaller"] = ModelKindName(c.smaller);
    cj["larger"] = ModelKindName(c.larger);
    if (!c.test.empty()) {
      cj["test"] = c.test;
      cj["statistic"] = c.statistic;
      cj["dof1"] = c.dof1;
      cj["dof2"] = c.dof2;
      cj["p_value"] = c.p_value;
      cj["rejected"] = c.rejected;
    }
    if (!c.note.empty()) cj["note"] = c.note;
    comparisons.push_back(std::move(cj));
  }
  j["comparisons"] = comparisons;
  if (m.type_b) {
    j["type_b"] = {{"source", m.type_b->source},
                   {"half_width_rad", m.type_b->half_width},
                   {"distribution", m.type_b->distribution},
                   {"u_rad", m.type_b->u},
                   {"terms", m.type_b->terms}};
  }
  return j;
}

// `gravity`: the accelerometer's (gravity_u.hpp) gives `gravity_uncertainty` and the
// `*_u_with_gravity` keys; nullptr for the gyroscope.
json SensorJson(const SensorCalibration& c, const GravityUncertainty* gravity) {
  const SensorModel& m = c.model;
  json j;
  j["model"] = ModelKindName(m.kind);
  j["input_unit"] = m.input_unit;
  j["output_unit"] = m.output_unit;
  j["bias"] = Vec(m.bias);
  j["bias_u"] = Vec(c.bias_u);
  j["scale"] = Vec(m.scale);
  j["scale_u"] = Vec(c.scale_u);
  std::vector<double> mis = m.misalignment;
  if (mis.empty()) mis.assign(static_cast<size_t>(MisalignmentCount(m.sensor)), 0.0);
  j["misalignment"] = mis;
  std::vector<double> mis_u = c.misalignment_u;
  if (mis_u.empty()) mis_u.assign(mis.size(), 0.0);
  j["misalignment_u"] = mis_u;
  j["matrix"] = Mat(c.M());
  j["matrix_u"] = Mat(c.matrix_u);
  j["sensitivity"] = Vec(c.sensitivity);
  j["sensitivity_u"] = Vec(c.sensitivity_u);
  if (m.has_temperature) {
    j["temperature"] = {{"t_ref_c", m.t_ref_c},
                        {"bias_per_c", Vec(m.bias_per_c)},
                        {"bias_per_c_u", Vec(c.bias_per_c_u)}};
  }
  if (c.static_pose_temperature) {
    const PoseTemperatureRange& t = *c.static_pose_temperature;
    j["static_pose_temperature"] = {
        {"min_c", t.min_c}, {"mean_c", t.mean_c}, {"max_c", t.max_c}, {"poses", t.poses}};
  }
  if (c.full_scale) j["full_scale"] = *c.full_scale;
  if (c.static_residuals) {
    j["static_residuals"] = {{"unit", c.static_residuals->unit},
                             {"before", c.static_residuals->before},
                             {"after", c.static_residuals->after}};
  }
  if (c.model_check) j["model_check"] = ModelCheckJson(*c.model_check);
  if (gravity != nullptr) {
    const GravityShare share = GravityShareOf(c, *gravity);
    j["gravity_uncertainty"] = {{"gravity_mps2", gravity->gravity_mps2},
                                {"u_mps2", gravity->u_mps2},
                                {"u_relative", gravity->Relative()},
                                {"basis", gravity->basis},
                                {"statement", gravity->statement}};
    j["scale_u_with_gravity"] = Vec(share.scale_u);
    j["sensitivity_u_with_gravity"] = Vec(share.sensitivity_u);
    j["matrix_u_with_gravity"] = Mat(share.matrix_u);
  }
  j["parameters"] = c.parameter_names;
  j["covariance"] = Mat(c.covariance);
  j["correlation"] = Mat(c.Correlation());
  j["dof"] = c.dof;
  j["reduced_chi2"] = c.reduced_chi2;
  j["coverage_factor_95"] = c.coverage_factor_95;
  j["residual_rms"] = c.residual_rms;
  j["residual_unit"] = c.residual_unit;
  json groups = json::array();
  for (const ResidualGroup& g : c.groups) {
    groups.push_back({{"kind", g.kind}, {"count", g.count}, {"rms", g.rms}, {"unit", g.unit}});
  }
  j["residual_groups"] = groups;
  json segs = json::array();
  for (const Segment& s : c.segments) segs.push_back(SegmentJson(s));
  j["segments"] = segs;
  return j;
}

// ---- Reader ------------------------------------------------------------------------------

Eigen::Vector3d Vec3(const JsonCursor& j) {
  if (!j.IsArray() || j.Size() != 3) {
    j.Fail("an array of 3 numbers");
    return Eigen::Vector3d::Zero();
  }
  return Eigen::Vector3d(j[0].Number(), j[1].Number(), j[2].Number());
}

std::vector<double> NumbersN(const JsonCursor& j, size_t n) {
  if (!j.IsArray() || j.Size() != n) {
    j.Fail(fmt::format("an array of {} numbers", n));
    return std::vector<double>(n, 0.0);
  }
  return j.Numbers();
}

// A square matrix: an array of n arrays of n numbers.
Eigen::MatrixXd SquareMatrix(const JsonCursor& j) {
  if (!j.IsArray()) {
    j.Fail("a square matrix (an array of rows of numbers)");
    return {};
  }
  const size_t n = j.Size();
  Eigen::MatrixXd m =
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (size_t r = 0; r < n; ++r) {
    const JsonCursor row = j[r];
    if (!row.IsArray() || row.Size() != n) {
      row.Fail(fmt::format("a row of {} numbers (a square matrix of {} rows)", n, n));
      return {};
    }
    for (size_t c = 0; c < n; ++c) {
      m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c].Number();
    }
  }
  return m;
}

// The redundant fields agree to double rounding (calibration_io.hpp): each element of
// `matrix` with t_ij k_j from `scale` and `misalignment`, each `sensitivity` with 1 / k.
void CheckRedundant(const JsonCursor& j, const SensorCalibration& c,
                    const Eigen::Matrix3d& file_matrix, const Eigen::Vector3d& file_sensitivity) {
  const auto agree = [](double a, double b) {
    return std::fabs(a - b) <= kRedundantRelTolerance * std::max(std::fabs(a), std::fabs(b));
  };
  const Eigen::Matrix3d tk = c.model.Matrix();
  for (size_t i = 0; i < 3; ++i) {
    for (size_t k = 0; k < 3; ++k) {
      const double file = file_matrix(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
      const double want = tk(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
      if (agree(file, want)) continue;
      j["matrix"][i][k].Fail(fmt::format(
          "T K = {:.17g} from 'scale' and 'misalignment' (difference {:.3g}, tolerance {:.3g} "
          "relative, the double rounding of both: the redundant fields disagree, "
          "docs/calibration-format.md)",
          want, file - want, kRedundantRelTolerance));
      return;
    }
  }
  for (size_t a = 0; a < 3; ++a) {
    const Eigen::Index e = static_cast<Eigen::Index>(a);
    if (agree(file_sensitivity[e], c.sensitivity[e])) continue;
    j["sensitivity"][a].Fail(fmt::format(
        "1 / scale[{}] = {:.17g} (tolerance {:.3g} relative: the redundant fields disagree)", a,
        c.sensitivity[e], kRedundantRelTolerance));
    return;
  }
}

// The standard uncertainties in the file are derived from its covariance (DeriveUncertainties):
// a covariance that is not a covariance, or a '*_u' field that says otherwise, is refused,
// so a hand-edited u never reaches a certificate or a blob. On success *c holds the derived
// values (matrix_u included, recomputed when the file has none).
void CheckUncertainties(const JsonCursor& j, SensorCalibration* c) {
  const SensorModel& m = c->model;
  const Eigen::Index expected = 3 + (m.kind != ModelKind::kBias ? 3 : 0) +
                                (m.kind == ModelKind::kFull ? MisalignmentCount(m.sensor) : 0) +
                                (m.has_temperature ? 3 : 0);
  const Eigen::MatrixXd& cov = c->covariance;
  if (cov.rows() != expected) {
    j["covariance"].Fail(fmt::format("a {} x {} matrix: the {} model{} has {} free parameters",
                                     expected, expected, ModelKindName(m.kind),
                                     m.has_temperature ? " with temperature" : "", expected));
    return;
  }
  for (Eigen::Index r = 0; r < cov.rows(); ++r) {
    for (Eigen::Index k = 0; k < cov.cols(); ++k) {
      // Symmetric to the rounding of a solver's covariance (Ceres' is not exactly symmetric:
      // 1e-14 relative in the golden files), relative to the two variances.
      const double a = cov(r, k), b = cov(k, r);
      const double scale = std::sqrt(std::fabs(cov(r, r) * cov(k, k)));
      if (!std::isfinite(a) || (r == k && a < 0.0) || std::fabs(a - b) > 1e-9 * scale) {
        j["covariance"][static_cast<size_t>(r)][static_cast<size_t>(k)].Fail(
            fmt::format("an element of a symmetric covariance matrix of finite numbers with a "
                        "non-negative diagonal (element [{}][{}] is {:.17g})",
                        k, r, b));
        return;
      }
    }
  }
  SensorCalibration derived = *c;
  DeriveUncertainties(&derived);
  // sqrt of the file's own diagonal: equal to rounding; matrix_u's central differences may
  // differ in the last digits between builds.
  const auto check = [&j](const JsonCursor& at, double file, double want, double rel) {
    if (!j.ok()) return;
    if (std::fabs(file - want) <= rel * std::max(std::fabs(file), std::fabs(want)) + 1e-300) return;
    at.Fail(fmt::format(
        "{:.17g}, the square root of its variance in the covariance (docs/calibration-format.md)",
        want));
  };
  for (size_t a = 0; a < 3; ++a) {
    const Eigen::Index e = static_cast<Eigen::Index>(a);
    check(j["bias_u"][a], c->bias_u[e], derived.bias_u[e], kRedundantRelTolerance);
    check(j["scale_u"][a], c->scale_u[e], derived.scale_u[e], kRedundantRelTolerance);
    if (m.has_temperature) {
      check(j["temperature"]["bias_per_c_u"][a], c->bias_per_c_u[e], derived.bias_per_c_u[e],
            kRedundantRelTolerance);
    }
  }
  for (size_t a = 0; a < c->misalignment_u.size() && a < derived.misalignment_u.size(); ++a) {
    check(j["misalignment_u"][a], c->misalignment_u[a], derived.misalignment_u[a],
          kRedundantRelTolerance);
  }
  if (j.Has("matrix_u")) {
    const Eigen::MatrixXd mu = SquareMatrix(j["matrix_u"]);
    if (j.ok() && mu.rows() != 3) j["matrix_u"].Fail("a 3 x 3 matrix");
    for (size_t r = 0; r < 3 && j.ok(); ++r) {
      for (size_t k = 0; k < 3; ++k) {
        const Eigen::Index er = static_cast<Eigen::Index>(r), ek = static_cast<Eigen::Index>(k);
        check(j["matrix_u"][r][k], mu(er, ek), derived.matrix_u(er, ek), 1e-6);
      }
    }
  }
  if (!j.ok()) return;
  c->matrix_u = derived.matrix_u;
  c->sensitivity_u = derived.sensitivity_u;
}

Segment SegmentFromJson(const JsonCursor& s) {
  Segment seg;
  if (!s.IsObject()) {
    s.Fail("an object (a segment)");
    return seg;
  }
  const std::string kind = s["kind"].OptionalString().value_or("static");
  bool known = false;
  for (SegmentKind k :
       {SegmentKind::kStatic, SegmentKind::kTable, SegmentKind::kRotation, SegmentKind::kSteady}) {
    if (kind == SegmentKindName(k)) {
      seg.kind = k;
      known = true;
    }
  }
  if (!known) s["kind"].Fail("static, table, rotation or steady_rotation");
  seg.piece = static_cast<int>(s["input"].OptionalInteger().value_or(0));
  seg.begin =
      static_cast<size_t>(std::max<int64_t>(0, s["begin_index"].OptionalInteger().value_or(0)));
  seg.end = static_cast<size_t>(std::max<int64_t>(0, s["end_index"].OptionalInteger().value_or(0)));
  seg.start_s = s["start_s"].OptionalNumber().value_or(0.0);
  seg.end_s = s["end_s"].OptionalNumber().value_or(0.0);
  seg.used = s.Has("used") ? s["used"].Bool() : true;
  seg.table_rate_dps = s["table_rate_dps"].OptionalNumber().value_or(0.0);
  seg.pose = static_cast<int>(s["pose"].OptionalInteger().value_or(0)) - 1;
  seg.steady_rate_dps = s["steady_rate_dps"].OptionalNumber().value_or(std::nan(""));
  seg.note = s["note"].OptionalString().value_or("");
  return seg;
}

std::vector<Segment> SegmentsFromJson(const JsonCursor& j) {
  std::vector<Segment> out;
  if (!j.Present()) return out;
  if (!j.IsArray()) {
    j.Fail("an array of segments");
    return out;
  }
  for (size_t i = 0; i < j.Size(); ++i) out.push_back(SegmentFromJson(j[i]));
  return out;
}

std::optional<ModelKind> ModelKindFromJson(const JsonCursor& j) {
  const std::optional<ModelKind> k = ParseModelKind(j.String());
  if (j.ok() && !k) j.Fail("\"bias\", \"scale\" or \"full\"");
  return k;
}

ModelCheck ModelCheckFromJson(const JsonCursor& j) {
  ModelCheck m;
  m.selection = j["selection"].String();
  m.status = j["status"].String();
  m.model_rejected = j["model_rejected"].Bool();
  m.chi2 = j["chi2"].OptionalNumber().value_or(-1.0);
  m.chi2_dof = j["chi2_dof"].OptionalNumber().value_or(0.0);
  m.p_value = j["p_value"].OptionalNumber().value_or(-1.0);
  m.reason = j["reason"].OptionalString().value_or("");
  const JsonCursor comparisons = j["comparisons"];
  if (!comparisons.IsArray()) comparisons.Fail("an array of model comparisons");
  for (size_t i = 0; i < comparisons.Size() && comparisons.IsArray(); ++i) {
    const JsonCursor cj = comparisons[i];
    ModelComparison c;
    c.smaller = ModelKindFromJson(cj["smaller"]).value_or(ModelKind::kScale);
    c.larger = ModelKindFromJson(cj["larger"]).value_or(ModelKind::kFull);
    c.test = cj["test"].OptionalString().value_or("");
    if (!c.test.empty()) {
      c.statistic = cj["statistic"].Number();
      c.dof1 = cj["dof1"].Number();
      c.dof2 = cj["dof2"].Number();
      c.p_value = cj["p_value"].Number();
      c.rejected = cj["rejected"].Bool();
    }
    c.note = cj["note"].OptionalString().value_or("");
    m.comparisons.push_back(std::move(c));
  }
  if (j.Has("type_b")) {
    const JsonCursor b = j["type_b"];
    CrossAxisTypeB t;
    t.source = b["source"].String();
    t.half_width = b["half_width_rad"].Number();
    t.distribution = b["distribution"].String();
    t.u = b["u_rad"].Number();
    t.terms = b["terms"].Strings();
    m.type_b = std::move(t);
  }
  return m;
}

// `gravity_uncertainty` and `*_u_with_gravity` (accelerometer) say what the file's gravity and
// u give (gravity_u.hpp), or the file is refused; they are derived, so nothing is kept.
void CheckGravityShare(const JsonCursor& j, const GravityUncertainty& gravity,
                       const SensorCalibration& c) {
  const JsonCursor g = j["gravity_uncertainty"];
  if (!g.IsObject()) {
    g.Fail("an object (the gravity value's uncertainty: gravity_mps2, u_mps2, basis)");
    return;
  }
  const auto agree = [](double a, double b, double rel) {
    return std::fabs(a - b) <= rel * std::max(std::fabs(a), std::fabs(b)) + 1e-300;
  };
  const double g_mps2 = g["gravity_mps2"].Number();
  const double u_mps2 = g["u_mps2"].Number();
  const std::string basis = g["basis"].String();
  if (!j.ok()) return;
  if (!agree(g_mps2, gravity.gravity_mps2, kRedundantRelTolerance)) {
    g["gravity_mps2"].Fail(fmt::format("{:.17g}, the file's gravity_mps2", gravity.gravity_mps2));
    return;
  }
  if (!agree(u_mps2, gravity.u_mps2, kRedundantRelTolerance) || basis != gravity.basis) {
    g["u_mps2"].Fail(fmt::format(
        "{:.17g} ({}), the u the file's gravity_mps2, gravity_source and gravity_u_mps2 give "
        "(docs/calibration-model.md \"Gravity\")",
        gravity.u_mps2, gravity.basis));
    return;
  }
  const GravityShare want = GravityShareOf(c, gravity);
  const std::pair<const char*, const Eigen::Vector3d*> vectors[] = {
      {"scale_u_with_gravity", &want.scale_u}, {"sensitivity_u_with_gravity", &want.sensitivity_u}};
  for (const auto& [key, w] : vectors) {
    const Eigen::Vector3d file = Vec3(j[key]);
    for (size_t a = 0; a < 3 && j.ok(); ++a) {
      const double v = (*w)[static_cast<Eigen::Index>(a)];
      if (!agree(file[static_cast<Eigen::Index>(a)], v, kRedundantRelTolerance)) {
        j[key][a].Fail(fmt::format("{:.17g}, sqrt(u^2 + (x u(g) / g)^2) of the file's values", v));
      }
    }
  }
  const Eigen::MatrixXd mu = SquareMatrix(j["matrix_u_with_gravity"]);
  if (j.ok() && mu.rows() != 3) j["matrix_u_with_gravity"].Fail("a 3 x 3 matrix");
  for (size_t r = 0; r < 3 && j.ok(); ++r) {
    for (size_t k = 0; k < 3 && j.ok(); ++k) {
      const double v = want.matrix_u(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k));
      // matrix_u's central differences may differ in the last digits between builds.
      if (!agree(mu(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(k)), v, 1e-6)) {
        j["matrix_u_with_gravity"][r][k].Fail(
            fmt::format("{:.17g}, sqrt(u^2 + (M u(g) / g)^2) of the file's values", v));
      }
    }
  }
}

std::optional<SensorCalibration> SensorFromJson(const JsonCursor& j, ImuSensor sensor,
                                                const GravityUncertainty& gravity) {
  if (!j.IsObject()) {
    j.Fail(fmt::format("an object (the {} calibration)", ImuSensorLongName(sensor)));
    return std::nullopt;
  }
  SensorCalibration c;
  SensorModel& m = c.model;
  m.sensor = sensor;
  const std::string kind = j["model"].String();
  if (!j.ok()) return std::nullopt;
  const std::optional<ModelKind> k = ParseModelKind(kind);
  if (!k) {
    j["model"].Fail("bias, scale or full");
    return std::nullopt;
  }
  m.kind = *k;
  m.input_unit = j["input_unit"].String();
  m.output_unit = j["output_unit"].String();
  const std::string expected_out(OutputUnit(sensor).symbol);
  if (j.ok() && m.output_unit != expected_out) {
    j["output_unit"].Fail(fmt::format("\"{}\"", expected_out));
  }
  if (j.ok() && !NominalScale(sensor, m.input_unit, 1.0)) {
    j["input_unit"].Fail(fmt::format("a unit of the {}", ImuSensorName(sensor)));
  }
  m.bias = Vec3(j["bias"]);
  c.bias_u = Vec3(j["bias_u"]);
  m.scale = Vec3(j["scale"]);
  c.scale_u = Vec3(j["scale_u"]);
  const size_t nm = static_cast<size_t>(MisalignmentCount(sensor));
  m.misalignment = NumbersN(j["misalignment"], nm);
  c.misalignment_u = NumbersN(j["misalignment_u"], nm);
  if (j.Has("temperature")) {
    const JsonCursor t = j["temperature"];
    m.has_temperature = true;
    m.t_ref_c = t["t_ref_c"].Number();
    m.bias_per_c = Vec3(t["bias_per_c"]);
    c.bias_per_c_u = Vec3(t["bias_per_c_u"]);
  }
  if (j.Has("full_scale")) {
    const JsonCursor fs = j["full_scale"];
    if (!(fs.IsNumber() && fs.Number() > 0.0) || m.input_unit != "LSB") {
      fs.Fail("a number > 0 (the full-scale setting of raw input: for input_unit LSB only)");
    } else {
      c.full_scale = fs.Number();
    }
  }
  if (j.Has("static_pose_temperature")) {
    const JsonCursor t = j["static_pose_temperature"];
    PoseTemperatureRange r;
    r.min_c = t["min_c"].Number();
    r.mean_c = t["mean_c"].Number();
    r.max_c = t["max_c"].Number();
    r.poses = static_cast<int>(t["poses"].Integer());
    if (j.ok() && !(std::isfinite(r.min_c) && r.min_c <= r.mean_c && r.mean_c <= r.max_c &&
                    std::isfinite(r.max_c) && r.poses >= 1)) {
      t.Fail("finite min_c <= mean_c <= max_c and poses >= 1");
    }
    c.static_pose_temperature = r;
  }
  if (j.Has("static_residuals")) {
    const JsonCursor r = j["static_residuals"];
    StaticResiduals s;
    s.unit = r["unit"].String();
    if (j.ok() && s.unit != expected_out) r["unit"].Fail(fmt::format("\"{}\"", expected_out));
    s.before = r["before"].Numbers();
    s.after = r["after"].Numbers();
    if (j.ok() && s.after.size() != s.before.size()) {
      r["after"].Fail(fmt::format("{} numbers, one per value of before", s.before.size()));
    }
    c.static_residuals = std::move(s);
  }
  if (j.Has("model_check")) c.model_check = ModelCheckFromJson(j["model_check"]);
  c.covariance = SquareMatrix(j["covariance"]);
  c.parameter_names = j["parameters"].Strings();
  if (j.ok() && static_cast<Eigen::Index>(c.parameter_names.size()) != c.covariance.rows()) {
    j["parameters"].Fail(fmt::format("{} names, one per row of covariance", c.covariance.rows()));
  }
  c.residual_rms = j["residual_rms"].Number();
  c.residual_unit = j["residual_unit"].String();
  c.dof = static_cast<int>(j["dof"].Integer());
  c.reduced_chi2 = j["reduced_chi2"].OptionalNumber().value_or(0.0);
  c.coverage_factor_95 = j["coverage_factor_95"].Number();
  if (!j.ok()) return std::nullopt;
  // Derived values are recomputed from the constants rather than trusted.
  for (size_t a = 0; a < 3; ++a) {
    const Eigen::Index e = static_cast<Eigen::Index>(a);
    if (!(m.scale[e] != 0 && std::isfinite(m.scale[e]))) {
      j["scale"][a].Fail("a finite non-zero number");
      return std::nullopt;
    }
    c.sensitivity[e] = 1.0 / m.scale[e];
    c.sensitivity_u[e] = c.scale_u[e] / (m.scale[e] * m.scale[e]);
  }
  // `matrix` is what the blob carries (docs/calibration-blob.md section 10) and what apply uses;
  // `scale` and `misalignment` (and `sensitivity`) say the same, or the file is refused.
  const Eigen::MatrixXd matrix = SquareMatrix(j["matrix"]);
  if (j.ok() && matrix.rows() != 3) j["matrix"].Fail("a 3 x 3 matrix");
  const Eigen::Vector3d sensitivity = j.Has("sensitivity") ? Vec3(j["sensitivity"]) : c.sensitivity;
  if (!j.ok()) return std::nullopt;
  c.matrix = Eigen::Matrix3d(matrix);
  CheckRedundant(j, c, *c.matrix, sensitivity);
  if (!j.ok()) return std::nullopt;
  CheckUncertainties(j, &c);
  if (!j.ok()) return std::nullopt;
  if (j.Has("gravity_uncertainty")) {
    if (sensor != ImuSensor::kAccel) {
      j["gravity_uncertainty"].Fail("absent: only the accelerometer is fitted to gravity");
      return std::nullopt;
    }
    CheckGravityShare(j, gravity, c);
    if (!j.ok()) return std::nullopt;
  }
  if (j.Has("residual_groups")) {
    const JsonCursor groups = j["residual_groups"];
    if (!groups.IsArray()) groups.Fail("an array of residual groups");
    for (size_t i = 0; i < groups.Size() && groups.IsArray(); ++i) {
      const JsonCursor g = groups[i];
      ResidualGroup rg;
      rg.kind = g["kind"].OptionalString().value_or("");
      rg.count = static_cast<int>(g["count"].OptionalInteger().value_or(0));
      rg.rms = g["rms"].OptionalNumber().value_or(0.0);
      rg.unit = g["unit"].OptionalString().value_or("");
      c.groups.push_back(rg);
    }
  }
  c.segments = SegmentsFromJson(j["segments"]);
  if (!j.ok()) return std::nullopt;
  return c;
}

InputFile InputFromJson(const JsonCursor& f) {
  InputFile in;
  if (!f.IsObject()) {
    f.Fail("an object (an input record)");
    return in;
  }
  in.path = f["path"].OptionalString().value_or("");
  in.sha256 = f["sha256"].OptionalString().value_or("");
  in.format = f["format"].OptionalString().value_or("");
  for (const char* key : {"start_utc", "end_utc"}) {
    const std::optional<std::string> v = f[key].OptionalString();
    if (!v) continue;
    if (!ParseUtcIso8601(*v)) {
      f[key].Fail("an ISO 8601 UTC time such as \"2026-05-01T12:00:00Z\"");
      continue;
    }
    (std::string_view(key) == "start_utc" ? in.start_utc : in.end_utc) = *v;
  }
  if (f.Has("duration_s")) {
    const JsonCursor d = f["duration_s"];
    if (!(d.IsNumber() && d.Number() >= 0.0)) {
      d.Fail("a number >= 0");
    } else {
      in.duration_s = d.Number();
    }
  }
  return in;
}

std::vector<RecordConditions> RecordConditionsFromJson(const JsonCursor& j) {
  std::vector<RecordConditions> out;
  if (!j.IsArray()) {
    j.Fail("an array of record conditions");
    return out;
  }
  for (size_t i = 0; i < j.Size(); ++i) {
    const JsonCursor r = j[i];
    RecordConditions rc;
    rc.input = static_cast<int>(r["input"].Integer());
    rc.samples = r["samples"].Integer();
    rc.duration_s = r["duration_s"].Number();
    rc.temp_min_c = r["temp_min_c"].OptionalNumber();
    rc.temp_max_c = r["temp_max_c"].OptionalNumber();
    if (j.ok() && (rc.input < 0 || rc.samples < 0)) r.Fail("input >= 0 and samples >= 0");
    if (j.ok() && rc.temp_min_c.has_value() != rc.temp_max_c.has_value()) {
      r.Fail("both temp_min_c and temp_max_c, or neither");
    }
    if (j.ok() && rc.temp_min_c && !(*rc.temp_min_c <= *rc.temp_max_c)) {
      r["temp_max_c"].Fail(fmt::format("a temperature >= temp_min_c {}", *rc.temp_min_c));
    }
    out.push_back(rc);
  }
  return out;
}

TagCalibration TagFromJson(const JsonCursor& tj, const GravityUncertainty& gravity) {
  TagCalibration t;
  if (!tj.IsObject()) {
    tj.Fail("an object (a tag calibration)");
    return t;
  }
  t.sensor = static_cast<int>(tj["sensor"].Integer());
  if (tj.Has("device_id")) {
    const std::string text = tj["device_id"].String();
    if (tj.ok()) {
      Result<uint64_t> id = ParseDeviceIdText(text);
      if (id.ok()) {
        t.device_id = id.value();
      } else {
        tj["device_id"].Fail("a device ID (" + id.error().message + ")");
      }
    }
  }
  t.name = tj["name"].OptionalString().value_or("");
  t.profile = tj["profile"].OptionalString().value_or("");
  if (!tj.Has("accel") && !tj.Has("gyro")) {
    tj.Fail("a tag calibration with 'accel' or 'gyro'");
    return t;
  }
  if (tj.Has("accel")) t.accel = SensorFromJson(tj["accel"], ImuSensor::kAccel, gravity);
  if (tj.Has("gyro") && tj.ok()) t.gyro = SensorFromJson(tj["gyro"], ImuSensor::kGyro, gravity);
  t.threshold_factor = tj["threshold_factor"].OptionalNumber().value_or(0.0);
  t.saturated_samples = static_cast<int>(tj["saturated_samples"].OptionalInteger().value_or(0));
  t.iterations = static_cast<int>(tj["iterations"].OptionalInteger().value_or(0));
  if (tj.Has("warnings")) t.warnings = tj["warnings"].Strings();
  t.segments = SegmentsFromJson(tj["segments_found"]);
  if (tj.Has("record_conditions")) {
    t.record_conditions = RecordConditionsFromJson(tj["record_conditions"]);
  }
  return t;
}

}  // namespace

json ToJsonValue(const Calibration& cal) {
  json j;
  j["schema"] = kCalibrationSchema;
  j["tool_version"] = cal.tool_version;
  j["date_utc"] = cal.date_utc;
  j["gravity_mps2"] = cal.gravity_mps2;
  if (!cal.gravity_source.empty()) j["gravity_source"] = cal.gravity_source;
  if (cal.gravity_u_mps2) j["gravity_u_mps2"] = *cal.gravity_u_mps2;
  json inputs = json::array();
  for (const InputFile& f : cal.inputs) {
    json in = {{"path", f.path}, {"sha256", f.sha256}};
    if (!f.format.empty()) in["format"] = f.format;
    if (f.duration_s) in["duration_s"] = *f.duration_s;
    if (!f.start_utc.empty()) in["start_utc"] = f.start_utc;
    if (!f.end_utc.empty()) in["end_utc"] = f.end_utc;
    inputs.push_back(in);
  }
  j["inputs"] = inputs;
  // The gravity value's u in the accelerometer's (issue #36 point 7), from the fields above.
  const GravityUncertainty gravity = GravityUncertaintyOf(cal);
  json tags = json::array();
  for (const TagCalibration& t : cal.tags) {
    json tj;
    tj["sensor"] = t.sensor;
    if (t.device_id) tj["device_id"] = FormatDeviceIdText(*t.device_id);
    if (!t.name.empty()) tj["name"] = t.name;
    if (!t.profile.empty()) tj["profile"] = t.profile;
    tj["threshold_factor"] = t.threshold_factor;
    tj["saturated_samples"] = t.saturated_samples;
    tj["iterations"] = t.iterations;
    tj["warnings"] = t.warnings;
    json segs = json::array();
    for (const Segment& s : t.segments) segs.push_back(SegmentJson(s));
    tj["segments_found"] = segs;
    if (t.record_conditions) {
      json records = json::array();
      for (const RecordConditions& r : *t.record_conditions) {
        json rj = {{"input", r.input}, {"samples", r.samples}, {"duration_s", r.duration_s}};
        if (r.temp_min_c) rj["temp_min_c"] = *r.temp_min_c;
        if (r.temp_max_c) rj["temp_max_c"] = *r.temp_max_c;
        records.push_back(std::move(rj));
      }
      tj["record_conditions"] = records;
    }
    if (t.accel) tj["accel"] = SensorJson(*t.accel, &gravity);
    if (t.gyro) tj["gyro"] = SensorJson(*t.gyro, nullptr);
    tags.push_back(tj);
  }
  j["tags"] = tags;
  if (cal.conformity) {
    j["conformity_rule"] = ConformityRuleToJson(*cal.conformity);
    j["conformity"] = ConformityEntriesToJson(*cal.conformity);
  }
  return j;
}
Calibration CalibrationFromJsonValue(const JsonCursor& j) {
  Calibration cal;
  if (!j.IsObject()) {
    j.Fail("an object (metro.calibration/1)");
    return cal;
  }
  const std::string schema = j["schema"].String();
  if (!j.ok()) return cal;
  if (schema != kCalibrationSchema) {
    j["schema"].Fail(fmt::format("\"{}\"", kCalibrationSchema));
    return cal;
  }
  cal.gravity_mps2 = j["gravity_mps2"].Number();
  cal.tool_version = j["tool_version"].OptionalString().value_or("");
  cal.date_utc = j["date_utc"].OptionalString().value_or("");
  // The date of the calibration goes into the blob and the certificate: refused here, at its
  // position, rather than when a blob is made (issue #37).
  if (j.ok() && !cal.date_utc.empty() && !ParseUtcIso8601(cal.date_utc)) {
    j["date_utc"].Fail("an ISO 8601 UTC time such as \"2026-05-01T12:00:00Z\"");
  }
  if (j.Has("gravity_source")) {
    cal.gravity_source = j["gravity_source"].String();
    if (j.ok() && cal.gravity_source != "standard" && cal.gravity_source != "given") {
      j["gravity_source"].Fail("\"standard\" or \"given\"");
    }
  }
  if (j.Has("gravity_u_mps2")) {
    cal.gravity_u_mps2 = j["gravity_u_mps2"].Number();
    if (j.ok() && !(*cal.gravity_u_mps2 >= 0 && *cal.gravity_u_mps2 < 0.5)) {
      j["gravity_u_mps2"].Fail("a standard uncertainty of gravity, 0 <= u < 0.5 m/s^2");
    }
  }
  if (j.Has("inputs")) {
    const JsonCursor inputs = j["inputs"];
    if (!inputs.IsArray()) inputs.Fail("an array of input records");
    for (size_t i = 0; i < inputs.Size() && inputs.IsArray(); ++i) {
      cal.inputs.push_back(InputFromJson(inputs[i]));
    }
  }
  const JsonCursor tags = j["tags"];
  if (!tags.IsArray() || tags.Size() == 0) {
    tags.Fail("a non-empty array of tag calibrations");
    return cal;
  }
  const GravityUncertainty gravity = GravityUncertaintyOf(cal);
  for (size_t i = 0; i < tags.Size() && j.ok(); ++i) {
    cal.tags.push_back(TagFromJson(tags[i], gravity));
  }
  if (j.ok() && (j.Has("conformity") || j.Has("conformity_rule"))) {
    cal.conformity = ConformityFromJsonValue(j["conformity"], j["conformity_rule"]);
  }
  return cal;
}

std::string ToJson(const Calibration& calibration) { return JsonText(ToJsonValue(calibration), 2); }

Result<Calibration> CalibrationFromJson(std::string_view text, const std::string& file) {
  Result<Calibration> cal = ReadJsonText<Calibration>(text, file, CalibrationFromJsonValue);
  if (!cal.ok()) return cal;
  // Kept for the checks made after reading (CalibrationErrorAt): positions are found in the
  // text only when an error is reported, so reading stays linear in the file.
  cal.value().source_file = file;
  cal.value().source_text = std::make_shared<const std::string>(text);
  return cal;
}

Error CalibrationErrorAt(const Calibration& calibration, const CalibrationPath& path,
                         std::string message) {
  if (calibration.source_file.empty() || calibration.source_text == nullptr) {
    return MakeError(std::move(message));
  }
  const std::vector<JsonPathStep> steps(path.begin(), path.end());
  const std::string& text = *calibration.source_text;
  const auto [line, column] = TextLineColumn(text, JsonValueOffset(text, steps));
  return MakeError(calibration.source_file, line, column, std::move(message));
}

Error NoSensorError(const Calibration& calibration, int sensor) {
  std::string have;
  for (const TagCalibration& t : calibration.tags) {
    have += (have.empty() ? "" : ", ") + std::to_string(t.sensor);
  }
  return CalibrationErrorAt(
      calibration, {std::string("tags")},
      fmt::format("calibration has no sensor {} (it has: {}); expected --sensor {}{}", sensor, have,
                  calibration.tags.empty() ? 0 : calibration.tags.front().sensor,
                  calibration.tags.size() > 1 ? " or another of its sensors" : ""));
}

CalibrationPath CalibrationTagPath(const Calibration& calibration, int sensor) {
  for (size_t i = 0; i < calibration.tags.size(); ++i) {
    if (calibration.tags[i].sensor == sensor) return {std::string("tags"), i};
  }
  return {std::string("tags")};
}

CalibrationPath CalibrationSensorPath(const Calibration& calibration, int sensor, ImuSensor imu) {
  CalibrationPath path = CalibrationTagPath(calibration, sensor);
  path.emplace_back(std::string(ImuSensorName(imu)));
  return path;
}

std::string FormatCalibrationJson(const Calibration& calibration) {
  return ToJson(calibration) + "\n";
}

std::string CalibrationCertificateId(const Calibration& calibration) {
  return Sha256Hex(FormatCalibrationJson(calibration)).substr(0, 16);
}

Result<Calibration> LoadCalibration(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok()) return text.error();
  return CalibrationFromJson(text.value(), path);
}

}  // namespace metro
