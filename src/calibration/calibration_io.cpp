#include "metro/calibration/calibration_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <string_view>
#include <utility>

#include "metro/core/device_id.hpp"
#include "metro/core/file.hpp"
#include "metro/core/json_text.hpp"
#include "metro/core/rounding.hpp"
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

json SensorJson(const SensorCalibration& c) {
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

// Typed access with errors that name the key path.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  bool failed() const { return !message_.empty(); }
  Error error() const { return MakeError(file_, 0, message_); }

  const json* Get(const json& j, const std::string& path, const char* key) {
    if (failed()) return nullptr;
    if (!j.is_object() || !j.contains(key)) {
      Fail(fmt::format("missing key '{}{}'", path, key));
      return nullptr;
    }
    return &j.at(key);
  }
  double Number(const json& j, const std::string& path, const char* key) {
    const json* v = Get(j, path, key);
    if (v == nullptr) return 0;
    if (!v->is_number()) {
      Fail(fmt::format("'{}{}' must be a number", path, key));
      return 0;
    }
    return v->get<double>();
  }
  std::string String(const json& j, const std::string& path, const char* key) {
    const json* v = Get(j, path, key);
    if (v == nullptr) return "";
    if (!v->is_string()) {
      Fail(fmt::format("'{}{}' must be a string", path, key));
      return "";
    }
    return v->get<std::string>();
  }
  std::vector<double> Numbers(const json& j, const std::string& path, const char* key, size_t n) {
    const json* v = Get(j, path, key);
    std::vector<double> out;
    if (v == nullptr) return out;
    if (!v->is_array() || (n != 0 && v->size() != n)) {
      Fail(fmt::format("'{}{}' must be an array of {} numbers", path, key, n));
      return out;
    }
    for (const json& e : *v) {
      if (!e.is_number()) {
        Fail(fmt::format("'{}{}' must contain numbers only", path, key));
        return {};
      }
      out.push_back(e.get<double>());
    }
    return out;
  }
  Eigen::Vector3d Vec3(const json& j, const std::string& path, const char* key) {
    const std::vector<double> v = Numbers(j, path, key, 3);
    return v.size() == 3 ? Eigen::Vector3d(v[0], v[1], v[2]) : Eigen::Vector3d::Zero();
  }
  Eigen::MatrixXd Matrix(const json& j, const std::string& path, const char* key) {
    const json* v = Get(j, path, key);
    if (v == nullptr) return {};
    if (!v->is_array()) {
      Fail(fmt::format("'{}{}' must be an array of rows", path, key));
      return {};
    }
    const size_t n = v->size();
    Eigen::MatrixXd m(n, n);
    for (size_t r = 0; r < n; ++r) {
      const json& row = (*v)[r];
      if (!row.is_array() || row.size() != n) {
        Fail(fmt::format("'{}{}' must be a square matrix", path, key));
        return {};
      }
      for (size_t c = 0; c < n; ++c) {
        if (!row[c].is_number()) {
          Fail(fmt::format("'{}{}' must contain numbers only", path, key));
          return {};
        }
        m(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = row[c].get<double>();
      }
    }
    return m;
  }
  void Fail(std::string message) {
    if (message_.empty()) message_ = std::move(message);
  }

 private:
  std::string file_;
  std::string message_;
};

// The redundant fields agree to double rounding (calibration_io.hpp): each element of
// `matrix` with t_ij k_j from `scale` and `misalignment`, each `sensitivity` with 1 / k.
void CheckRedundant(Reader* rd, const std::string& path, const SensorCalibration& c,
                    const Eigen::Matrix3d& file_matrix, const Eigen::Vector3d& file_sensitivity) {
  const auto agree = [](double a, double b) {
    return std::fabs(a - b) <= kRedundantRelTolerance * std::max(std::fabs(a), std::fabs(b));
  };
  const Eigen::Matrix3d tk = c.model.Matrix();
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (agree(file_matrix(i, k), tk(i, k))) continue;
      rd->Fail(fmt::format(
          "'{}matrix'[{}][{}] is {:.17g} but 'scale' and 'misalignment' give T K = {:.17g} "
          "(difference {:.3g}, tolerance {:.3g} relative, the double rounding of both): the "
          "redundant fields disagree; expected matrix = T K (docs/calibration-format.md)",
          path, i, k, file_matrix(i, k), tk(i, k), file_matrix(i, k) - tk(i, k),
          kRedundantRelTolerance));
      return;
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (agree(file_sensitivity[a], c.sensitivity[a])) continue;
    rd->Fail(fmt::format(
        "'{}sensitivity'[{}] is {:.17g} but 1 / 'scale'[{}] is {:.17g} (tolerance {:.3g} "
        "relative): the redundant fields disagree; expected sensitivity = 1 / scale",
        path, a, file_sensitivity[a], a, c.sensitivity[a], kRedundantRelTolerance));
    return;
  }
}

// The standard uncertainties in the file are derived from its covariance (DeriveUncertainties):
// a covariance that is not a covariance, or a '*_u' field that says otherwise, is refused,
// so a hand-edited u never reaches a certificate or a blob. On success *c holds the derived
// values (matrix_u included, recomputed when the file has none).
void CheckUncertainties(Reader* rd, const std::string& path, const json& j, SensorCalibration* c) {
  const SensorModel& m = c->model;
  const Eigen::Index expected = 3 + (m.kind != ModelKind::kBias ? 3 : 0) +
                                (m.kind == ModelKind::kFull ? MisalignmentCount(m.sensor) : 0) +
                                (m.has_temperature ? 3 : 0);
  const Eigen::MatrixXd& cov = c->covariance;
  if (cov.rows() != expected) {
    rd->Fail(fmt::format("'{}covariance' is {} x {}; the {} model{} has {} free parameters", path,
                         cov.rows(), cov.cols(), ModelKindName(m.kind),
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
        rd->Fail(fmt::format(
            "'{}covariance'[{}][{}] is {:.17g}: expected a symmetric matrix of finite numbers "
            "with a non-negative diagonal",
            path, r, k, a));
        return;
      }
    }
  }
  SensorCalibration derived = *c;
  DeriveUncertainties(&derived);
  // sqrt of the file's own diagonal: equal to rounding; matrix_u's central differences may
  // differ in the last digits between builds.
  const auto check = [&](const std::string& key, const std::string& index, double file, double want,
                         double rel) {
    if (rd->failed()) return;
    if (std::fabs(file - want) <= rel * std::max(std::fabs(file), std::fabs(want)) + 1e-300) return;
    rd->Fail(fmt::format(
        "'{}{}'{} is {:.17g} but the covariance gives {:.17g}: a standard uncertainty must be "
        "the square root of its variance (docs/calibration-format.md)",
        path, key, index, file, want));
  };
  for (int a = 0; a < 3; ++a) {
    check("bias_u", fmt::format("[{}]", a), c->bias_u[a], derived.bias_u[a],
          kRedundantRelTolerance);
    check("scale_u", fmt::format("[{}]", a), c->scale_u[a], derived.scale_u[a],
          kRedundantRelTolerance);
    if (m.has_temperature) {
      check("temperature.bias_per_c_u", fmt::format("[{}]", a), c->bias_per_c_u[a],
            derived.bias_per_c_u[a], kRedundantRelTolerance);
    }
  }
  for (size_t a = 0; a < c->misalignment_u.size() && a < derived.misalignment_u.size(); ++a) {
    check("misalignment_u", fmt::format("[{}]", a), c->misalignment_u[a], derived.misalignment_u[a],
          kRedundantRelTolerance);
  }
  if (j.contains("matrix_u")) {
    const Eigen::MatrixXd mu = rd->Matrix(j, path, "matrix_u");
    if (!rd->failed() && mu.rows() != 3) rd->Fail(fmt::format("'{}matrix_u' must be 3 x 3", path));
    for (int r = 0; r < 3 && !rd->failed(); ++r) {
      for (int k = 0; k < 3; ++k) {
        check("matrix_u", fmt::format("[{}][{}]", r, k), mu(r, k), derived.matrix_u(r, k), 1e-6);
      }
    }
  }
  if (rd->failed()) return;
  c->matrix_u = derived.matrix_u;
  c->sensitivity_u = derived.sensitivity_u;
}

std::optional<SensorCalibration> ParseSensor(Reader* rd, const json& j, const std::string& path,
                                             ImuSensor sensor) {
  SensorCalibration c;
  SensorModel& m = c.model;
  m.sensor = sensor;
  const std::string kind = rd->String(j, path, "model");
  if (rd->failed()) return std::nullopt;
  const std::optional<ModelKind> k = ParseModelKind(kind);
  if (!k) {
    rd->Fail(fmt::format("'{}model' is '{}'; expected bias, scale or full", path, kind));
    return std::nullopt;
  }
  m.kind = *k;
  m.input_unit = rd->String(j, path, "input_unit");
  m.output_unit = rd->String(j, path, "output_unit");
  const std::string expected_out(OutputUnit(sensor).symbol);
  if (!rd->failed() && m.output_unit != expected_out) {
    rd->Fail(
        fmt::format("'{}output_unit' is '{}'; expected '{}'", path, m.output_unit, expected_out));
  }
  if (!rd->failed() && !NominalScale(sensor, m.input_unit, 1.0)) {
    rd->Fail(fmt::format("'{}input_unit' '{}' is not a unit of the {}", path, m.input_unit,
                         ImuSensorName(sensor)));
  }
  m.bias = rd->Vec3(j, path, "bias");
  c.bias_u = rd->Vec3(j, path, "bias_u");
  m.scale = rd->Vec3(j, path, "scale");
  c.scale_u = rd->Vec3(j, path, "scale_u");
  const size_t nm = static_cast<size_t>(MisalignmentCount(sensor));
  m.misalignment = rd->Numbers(j, path, "misalignment", nm);
  c.misalignment_u = rd->Numbers(j, path, "misalignment_u", nm);
  if (j.contains("temperature")) {
    const json& t = j.at("temperature");
    const std::string tp = path + "temperature.";
    m.has_temperature = true;
    m.t_ref_c = rd->Number(t, tp, "t_ref_c");
    m.bias_per_c = rd->Vec3(t, tp, "bias_per_c");
    c.bias_per_c_u = rd->Vec3(t, tp, "bias_per_c_u");
  }
  if (j.contains("full_scale")) {
    const json& fs = j.at("full_scale");
    if (!fs.is_number() || !(fs.get<double>() > 0.0) || m.input_unit != "LSB") {
      rd->Fail(fmt::format("'{}full_scale' must be a number > 0, for input_unit LSB only", path));
    } else {
      c.full_scale = fs.get<double>();
    }
  }
  if (j.contains("static_pose_temperature")) {
    const json& t = j.at("static_pose_temperature");
    const std::string tp = path + "static_pose_temperature.";
    PoseTemperatureRange r;
    r.min_c = rd->Number(t, tp, "min_c");
    r.mean_c = rd->Number(t, tp, "mean_c");
    r.max_c = rd->Number(t, tp, "max_c");
    r.poses = static_cast<int>(rd->Number(t, tp, "poses"));
    if (!rd->failed() && !(std::isfinite(r.min_c) && r.min_c <= r.mean_c && r.mean_c <= r.max_c &&
                           std::isfinite(r.max_c) && r.poses >= 1)) {
      rd->Fail(
          fmt::format("'{}static_pose_temperature' must have finite min_c <= mean_c <= "
                      "max_c and poses >= 1",
                      path));
    }
    c.static_pose_temperature = r;
  }
  c.covariance = rd->Matrix(j, path, "covariance");
  const json* names = rd->Get(j, path, "parameters");
  if (names != nullptr) {
    if (!names->is_array()) {
      rd->Fail(fmt::format("'{}parameters' must be an array of names", path));
    } else {
      for (const json& n : *names) {
        if (n.is_string()) c.parameter_names.push_back(n.get<std::string>());
      }
    }
  }
  if (!rd->failed() && static_cast<Eigen::Index>(c.parameter_names.size()) != c.covariance.rows()) {
    rd->Fail(fmt::format("'{}covariance' has {} rows for {} parameters", path, c.covariance.rows(),
                         c.parameter_names.size()));
  }
  c.residual_rms = rd->Number(j, path, "residual_rms");
  c.residual_unit = rd->String(j, path, "residual_unit");
  c.dof = static_cast<int>(rd->Number(j, path, "dof"));
  c.reduced_chi2 = j.value("reduced_chi2", 0.0);
  c.coverage_factor_95 = rd->Number(j, path, "coverage_factor_95");
  if (rd->failed()) return std::nullopt;
  // Derived values are recomputed from the constants rather than trusted.
  for (int a = 0; a < 3; ++a) {
    if (!(m.scale[a] != 0 && std::isfinite(m.scale[a]))) {
      rd->Fail(fmt::format("'{}scale' must be finite and non-zero", path));
      return std::nullopt;
    }
    c.sensitivity[a] = 1.0 / m.scale[a];
    c.sensitivity_u[a] = c.scale_u[a] / (m.scale[a] * m.scale[a]);
  }
  // `matrix` is what the blob carries (docs/calibration-blob.md section 10) and what apply uses;
  // `scale` and `misalignment` (and `sensitivity`) say the same, or the file is refused.
  const Eigen::MatrixXd matrix = rd->Matrix(j, path, "matrix");
  if (!rd->failed() && matrix.rows() != 3) {
    rd->Fail(fmt::format("'{}matrix' must be 3 x 3", path));
  }
  const Eigen::Vector3d sensitivity =
      j.contains("sensitivity") ? rd->Vec3(j, path, "sensitivity") : c.sensitivity;
  if (rd->failed()) return std::nullopt;
  c.matrix = Eigen::Matrix3d(matrix);
  CheckRedundant(rd, path, c, *c.matrix, sensitivity);
  if (rd->failed()) return std::nullopt;
  CheckUncertainties(rd, path, j, &c);
  if (rd->failed()) return std::nullopt;
  if (j.contains("residual_groups") && j.at("residual_groups").is_array()) {
    for (const json& g : j.at("residual_groups")) {
      ResidualGroup rg;
      rg.kind = g.value("kind", "");
      rg.count = g.value("count", 0);
      rg.rms = g.value("rms", 0.0);
      rg.unit = g.value("unit", "");
      c.groups.push_back(rg);
    }
  }
  if (j.contains("segments") && j.at("segments").is_array()) {
    for (const json& s : j.at("segments")) {
      Segment seg;
      const std::string kind_name = s.value("kind", "static");
      seg.kind = kind_name == "table"             ? SegmentKind::kTable
                 : kind_name == "rotation"        ? SegmentKind::kRotation
                 : kind_name == "steady_rotation" ? SegmentKind::kSteady
                                                  : SegmentKind::kStatic;
      seg.piece = s.value("input", 0);
      seg.begin = s.value("begin_index", size_t{0});
      seg.end = s.value("end_index", size_t{0});
      seg.start_s = s.value("start_s", 0.0);
      seg.end_s = s.value("end_s", 0.0);
      seg.used = s.value("used", true);
      seg.table_rate_dps = s.value("table_rate_dps", 0.0);
      seg.pose = s.value("pose", 0) - 1;
      seg.steady_rate_dps = s.value("steady_rate_dps", std::nan(""));
      seg.note = s.value("note", "");
      c.segments.push_back(seg);
    }
  }
  return c;
}

std::string Fixed(double v, int digits) { return fmt::format("{:.{}g}", v, digits); }

// JCGM 100:2008 7.2.2 concise notation: "826.6(5.0)", never "826.6026 (50)".
std::string ValueU(double v, double u) {
  if (u > 0) return ConciseNotation(v, u);
  return fmt::format("{:.7g} (fixed)", v);
}

void ReportSensor(const SensorCalibration& c, std::string* out) {
  const SensorModel& m = c.model;
  const char* axes = "xyz";
  *out += fmt::format("  {}: model {}, {} -> {}\n", ImuSensorName(m.sensor), ModelKindName(m.kind),
                      m.input_unit, m.output_unit);
  *out += fmt::format(
      "    calibrated = T K (raw - b); standard uncertainties (k = 1) in "
      "brackets; k95 = {:.3f} (dof {})\n",
      c.coverage_factor_95, c.dof);
  for (int a = 0; a < 3; ++a) {
    *out += fmt::format("    b_{}  = {} {}    k_{} = {} {}/{}\n", axes[a],
                        ValueU(m.bias[a], c.bias_u[a]), m.input_unit, axes[a],
                        ValueU(m.scale[a], c.scale_u[a]), m.output_unit, m.input_unit);
  }
  const char* const acc_names[] = {"a_yz", "a_zy", "a_zx"};
  const char* const gyr_names[] = {"g_yz", "g_zy", "g_xz", "g_zx", "g_xy", "g_yx"};
  const char* const* names = m.sensor == ImuSensor::kAccel ? acc_names : gyr_names;
  for (size_t i = 0; i < m.misalignment.size(); ++i) {
    const double u = i < c.misalignment_u.size() ? c.misalignment_u[i] : 0.0;
    *out += fmt::format("    {} = {} rad\n", names[i], ValueU(m.misalignment[i], u));
  }
  if (m.has_temperature) {
    *out += fmt::format("    temperature: t_ref = {:.2f} degC\n", m.t_ref_c);
    for (int a = 0; a < 3; ++a) {
      *out += fmt::format("    b1_{} = {} {}/degC\n", axes[a],
                          ValueU(m.bias_per_c[a], c.bias_per_c_u[a]), m.input_unit);
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

// Applies one sensor calibration to `tag`; with a temp_c column, *count receives how its
// temperatures met the validity range.
Status ApplySensor(const SensorCalibration& c, const TemperatureValidity& validity,
                   const std::string& file, Tag* tag,
                   std::optional<SensorTemperatureCount>* count) {
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
      return MakeError(file, 0,
                       fmt::format("sensor {}: the {} calibration takes {} input (_{} columns) "
                                   "but the session has no {} column",
                                   tag->sensor, ImuSensorName(sensor), c.model.input_unit,
                                   InputUnit(sensor, c.model.input_unit)->suffix, name));
    }
  }
  const Quantity* temp = FindColumn(*tag, "temp_c");
  if (c.model.has_temperature && temp == nullptr) {
    return MakeError(file, 0,
                     fmt::format("sensor {}: the {} calibration has a temperature term but the "
                                 "session has no temp_c column",
                                 tag->sensor, ImuSensorName(sensor)));
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

json CalibrationToJson(const Calibration& cal) {
  json j;
  j["schema"] = kCalibrationSchema;
  j["tool_version"] = cal.tool_version;
  j["date_utc"] = cal.date_utc;
  j["gravity_mps2"] = cal.gravity_mps2;
  if (!cal.gravity_source.empty()) j["gravity_source"] = cal.gravity_source;
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
    if (t.accel) tj["accel"] = SensorJson(*t.accel);
    if (t.gyro) tj["gyro"] = SensorJson(*t.gyro);
    tags.push_back(tj);
  }
  j["tags"] = tags;
  if (cal.conformity) {
    j["conformity_rule"] = ConformityRuleToJson(*cal.conformity);
    j["conformity"] = ConformityEntriesToJson(*cal.conformity);
  }
  return j;
}

Result<Calibration> CalibrationFromJson(const json& j, const std::string& file) {
  Reader rd(file);
  Calibration cal;
  const std::string schema = rd.String(j, "", "schema");
  if (rd.failed()) return rd.error();
  if (schema != kCalibrationSchema) {
    return MakeError(file, 0,
                     fmt::format("schema is '{}'; expected '{}'", schema, kCalibrationSchema));
  }
  cal.gravity_mps2 = rd.Number(j, "", "gravity_mps2");
  cal.tool_version = j.value("tool_version", "");
  cal.date_utc = j.value("date_utc", "");
  if (j.contains("gravity_source")) {
    const json& g = j.at("gravity_source");
    if (!g.is_string() || (g != "standard" && g != "given")) {
      return MakeError(file, 0, "'gravity_source': expected \"standard\" or \"given\"");
    }
    cal.gravity_source = g.get<std::string>();
  }
  if (j.contains("inputs") && j.at("inputs").is_array()) {
    const json& inputs = j.at("inputs");
    for (size_t i = 0; i < inputs.size(); ++i) {
      const json& f = inputs[i];
      if (!f.is_object())
        return MakeError(file, 0, fmt::format("'inputs[{}]': expected an object", i));
      InputFile in;
      in.path = f.value("path", "");
      in.sha256 = f.value("sha256", "");
      for (auto [key, field] :
           {std::pair{"format", &in.format}, std::pair{"start_utc", &in.start_utc},
            std::pair{"end_utc", &in.end_utc}}) {
        if (!f.contains(key)) continue;
        const json& v = f.at(key);
        const bool date = std::string_view(key) != "format";
        if (!v.is_string() || (date && !ParseUtcIso8601(v.get<std::string>()))) {
          return MakeError(
              file, 0,
              fmt::format(
                  "'inputs[{}].{}': expected {}", i, key,
                  date ? "an ISO 8601 UTC time such as \"2026-05-01T12:00:00Z\"" : "a string"));
        }
        *field = v.get<std::string>();
      }
      if (f.contains("duration_s")) {
        const json& d = f.at("duration_s");
        if (!d.is_number() || !(d.get<double>() >= 0.0)) {
          return MakeError(file, 0,
                           fmt::format("'inputs[{}].duration_s': expected a number >= 0", i));
        }
        in.duration_s = d.get<double>();
      }
      cal.inputs.push_back(std::move(in));
    }
  }
  const json* tags = rd.Get(j, "", "tags");
  if (rd.failed()) return rd.error();
  if (!tags->is_array() || tags->empty()) {
    return MakeError(file, 0, "'tags' must be a non-empty array");
  }
  for (size_t i = 0; i < tags->size(); ++i) {
    const json& tj = (*tags)[i];
    const std::string path = fmt::format("tags[{}].", i);
    TagCalibration t;
    t.sensor = static_cast<int>(rd.Number(tj, path, "sensor"));
    if (rd.failed()) return rd.error();
    if (tj.contains("device_id")) {
      const json& d = tj.at("device_id");
      Result<uint64_t> id = d.is_string() ? ParseDeviceIdText(d.get<std::string>())
                                          : Result<uint64_t>(MakeError("expected a string"));
      if (!id.ok()) {
        return MakeError(file, 0, fmt::format("'{}device_id': {}", path, id.error().message));
      }
      t.device_id = id.value();
    }
    for (auto [key, field] : {std::pair{"name", &t.name}, std::pair{"profile", &t.profile}}) {
      if (!tj.contains(key)) continue;
      if (!tj.at(key).is_string()) {
        return MakeError(file, 0, fmt::format("'{}{}': expected a string", path, key));
      }
      *field = tj.at(key).get<std::string>();
    }
    if (!tj.contains("accel") && !tj.contains("gyro")) {
      return MakeError(file, 0, fmt::format("'{}' has neither 'accel' nor 'gyro'", path));
    }
    if (tj.contains("accel")) {
      t.accel = ParseSensor(&rd, tj.at("accel"), path + "accel.", ImuSensor::kAccel);
    }
    if (tj.contains("gyro") && !rd.failed()) {
      t.gyro = ParseSensor(&rd, tj.at("gyro"), path + "gyro.", ImuSensor::kGyro);
    }
    if (rd.failed()) return rd.error();
    t.threshold_factor = tj.value("threshold_factor", 0.0);
    t.saturated_samples = tj.value("saturated_samples", 0);
    t.iterations = tj.value("iterations", 0);
    if (tj.contains("warnings") && tj.at("warnings").is_array()) {
      for (const json& w : tj.at("warnings")) {
        if (w.is_string()) t.warnings.push_back(w.get<std::string>());
      }
    }
    cal.tags.push_back(std::move(t));
  }
  if (j.contains("conformity") || j.contains("conformity_rule")) {
    Result<ConformityStatement> c =
        ConformityFromJson(j.value("conformity", json()), j.value("conformity_rule", json()), file);
    if (!c.ok()) return c.error();
    cal.conformity = std::move(c).value();
  }
  return cal;
}

std::string FormatCalibrationJson(const Calibration& calibration) {
  return JsonText(CalibrationToJson(calibration), 2) + "\n";
}

std::string CalibrationCertificateId(const Calibration& calibration) {
  return Sha256Hex(FormatCalibrationJson(calibration)).substr(0, 16);
}

Result<Calibration> LoadCalibration(const std::string& path) {
  Result<std::string> text = ReadFile(path);
  if (!text.ok()) return text.error();
  Result<json> j = ParseJsonText(text.value(), path);
  if (!j.ok()) return j.error();
  return CalibrationFromJson(j.value(), path);
}

std::string FormatCalibrationReport(const Calibration& cal) {
  std::string out;
  out +=
      fmt::format("calibration ({}), {}, {}\n", kCalibrationSchema, cal.tool_version, cal.date_utc);
  out += fmt::format("gravity {} m/s^2\n", cal.gravity_mps2);
  for (const InputFile& f : cal.inputs) {
    out += fmt::format("input {} sha256 {}\n", f.path, f.sha256);
  }
  for (const TagCalibration& t : cal.tags) {
    out += fmt::format("sensor {}: static detector factor {}, {} saturated samples excluded\n",
                       t.sensor, t.threshold_factor, t.saturated_samples);
    if (t.accel) ReportSensor(*t.accel, &out);
    if (t.gyro) ReportSensor(*t.gyro, &out);
    for (const std::string& w : t.warnings) out += "  warning: " + w + "\n";
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
      Status s = ApplySensor(**c, validity.value(), session->path, &tag, &count);
      if (!s.ok()) return s.error();
      if (count) summary.temperature.push_back(*count);
    }
    ++summary.tags_calibrated;
    summary.rows += static_cast<int64_t>(tag.size());
  }
  return summary;
}

}  // namespace metro
