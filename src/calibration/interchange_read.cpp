// Reading the interchange formats' files (interchange.hpp, ReadInterchangeFile): each number of
// the format's layout with its position, unknown and missing keys refused at file:line:column.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>

#include "calibration/interchange_forms.hpp"
#include "core/json_reader.hpp"
#include "core/nearest_name.hpp"
#include "core/yaml_document.hpp"
#include "metro/calibration/interchange.hpp"
#include "metro/core/file.hpp"

namespace metro {
namespace {

namespace ii = interchange_internal;

// The file being filled: values in layout order and where each was read.
struct Filling {
  InterchangeFile out;
  std::vector<std::pair<int64_t, int64_t>> positions;
  std::map<std::string, size_t> index;  // name -> layout index

  Filling(InterchangeFormat format, int instance, const std::string& file) {
    out.format = format;
    out.file = file;
    out.values = ii::Layout(format, instance);
    out.present.assign(out.values.size(), false);
    positions.assign(out.values.size(), {1, 1});
    for (size_t i = 0; i < out.values.size(); ++i) index[out.values[i].name] = i;
  }
  void Set(const std::string& name, double v, int64_t line, int64_t column) {
    const size_t i = index.at(name);
    out.values[i].value = v;
    out.present[i] = true;
    positions[i] = {line, column};
  }
};

Error YamlError(const std::string& file, const YamlNode& at, const std::string& path,
                const std::string& message) {
  return MakeError(file, at.line, at.column, fmt::format("{}: {}", path, message));
}

// Orthonormal with det +1 to 1e-6: what a rotation read from a file must be.
bool IsRotation(const Eigen::Matrix3d& r) {
  return (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-6 &&
         r.determinant() > 0.0;
}

// A 3 x 3 matrix written as a sequence of three rows of three numbers.
Status ReadYamlMatrix(const YamlNode& node, const std::string& path, Filling* f,
                      bool rotation = false) {
  const std::string& file = f->out.file;
  if (!node.IsSequence() || node.items.size() != 3) {
    return YamlError(file, node, path,
                     fmt::format("expected a 3 x 3 matrix (three rows `- [a, b, c]`), found {}",
                                 node.Describe()));
  }
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    const YamlNode& row = node.items[static_cast<size_t>(r)];
    if (!row.IsSequence() || row.items.size() != 3) {
      return YamlError(file, row, fmt::format("{}[{}]", path, r),
                       fmt::format("expected a row of 3 numbers, found {}", row.Describe()));
    }
    for (int c = 0; c < 3; ++c) {
      const YamlNode& x = row.items[static_cast<size_t>(c)];
      const std::optional<double> v = x.Number();
      const std::string name = fmt::format("{}[{}][{}]", path, r, c);
      if (!v)
        return YamlError(file, x, name, fmt::format("expected a number, found {}", x.Describe()));
      m(r, c) = *v;
      f->Set(name, *v, x.line, x.column);
    }
  }
  if (rotation && !IsRotation(m)) {
    return YamlError(
        file, node, path,
        fmt::format("expected a rotation matrix (R^T R = I to 1e-6, det +1), found "
                    "|R^T R - I| = {:.3g}, det {:.6g}",
                    (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
                    m.determinant()));
  }
  return {};
}

// Unknown keys of a mapping refused with the ones expected.
Status CheckKeys(const YamlNode& node, const std::string& path, const std::set<std::string>& known,
                 const std::string& file) {
  if (!node.IsMapping()) {
    return YamlError(file, node, path,
                     fmt::format("expected a mapping, found {}", node.Describe()));
  }
  std::set<std::string> seen;
  for (const auto& [k, v] : node.members) {
    const std::string name = path.empty() ? k.scalar : path + "." + k.scalar;
    if (!k.IsScalar() || known.count(k.scalar) == 0) {
      return YamlError(
          file, k, name,
          fmt::format("unknown key (nearest: {}); expected one of: {}",
                      Nearest(k.scalar, {known.begin(), known.end()}), fmt::join(known, ", ")));
    }
    if (!seen.insert(k.scalar).second) return YamlError(file, k, name, "a duplicate key");
  }
  return {};
}

const std::set<std::string> kNoiseKeys = {"T_i_b",
                                          "accelerometer_noise_density",
                                          "accelerometer_random_walk",
                                          "gyroscope_noise_density",
                                          "gyroscope_random_walk",
                                          "model",
                                          "rostopic",
                                          "time_offset",
                                          "update_rate"};

// The imuN node of an imu-chain yaml, or the root when it is one imu's keys (Kalibr's imu.yaml).
Result<const YamlNode*> ImuNode(const YamlNode& root, int instance, const std::string& file,
                                const std::set<std::string>& imu_keys) {
  if (!root.IsMapping()) {
    return YamlError(file, root, "(top)",
                     fmt::format("expected a mapping, found {}", root.Describe()));
  }
  bool chain = false;
  for (const auto& [k, v] : root.members) {
    if (k.scalar.rfind("imu", 0) == 0 && k.scalar.size() > 3 &&
        std::all_of(k.scalar.begin() + 3, k.scalar.end(), [](char c) { return std::isdigit(c); })) {
      chain = true;
    } else if (imu_keys.count(k.scalar) == 0) {
      return YamlError(file, k, k.scalar,
                       fmt::format("unknown key; expected imu0, imu1, ... (an imu-chain yaml) or "
                                   "one imu's keys: {}",
                                   fmt::join(imu_keys, ", ")));
    }
  }
  if (!chain) return &root;
  const std::string want = fmt::format("imu{}", instance);
  const YamlNode* imu = root.Find(want);
  if (imu == nullptr) {
    return YamlError(file, root, want, "missing: the file has no such imu (give --instance)");
  }
  return imu;
}

Status RequireMatrix(const YamlNode& parent, const std::string& key, const std::string& path,
                     Filling* f, bool rotation = false) {
  const YamlNode* node = parent.Find(key);
  if (node == nullptr) {
    return YamlError(f->out.file, parent, path + "." + key, "missing (a 3 x 3 matrix)");
  }
  return ReadYamlMatrix(*node, path + "." + key, f, rotation);
}

void NoteNoiseKeys(const YamlNode& imu, Filling* f) {
  for (const auto& [k, v] : imu.members) {
    if (k.scalar.find("noise_density") != std::string::npos ||
        k.scalar.find("random_walk") != std::string::npos) {
      f->out.notes.push_back(fmt::format(
          "{} (noise: read by characterize noise-compare, not a calibration constant)", k.scalar));
    }
  }
}

// The imu<instance> node of a Kalibr-style IMU chain (Kalibr, OpenVINS) with its keys
// checked against `keys` and the noise keys, the noise keys noted, and its `model` (or
// `fallback`) one of `models`, into f->out.model.
Result<const YamlNode*> ChainImu(const YamlNode& root, int instance,
                                 const std::set<std::string>& own_keys, const std::string& fallback,
                                 const std::set<std::string>& models, Filling* f) {
  std::set<std::string> keys = kNoiseKeys;
  keys.insert(own_keys.begin(), own_keys.end());
  Result<const YamlNode*> imu_r = ImuNode(root, instance, f->out.file, keys);
  if (!imu_r.ok()) return imu_r.error();
  const YamlNode& imu = *imu_r.value();
  const std::string p = fmt::format("imu{}", instance);
  if (Status s = CheckKeys(imu, p, keys, f->out.file); !s.ok()) return s.error();
  NoteNoiseKeys(imu, f);
  const YamlNode* model = imu.Find("model");
  f->out.model = model != nullptr ? model->scalar : fallback;
  if (model != nullptr && (!model->IsScalar() || models.count(model->scalar) == 0)) {
    return YamlError(
        f->out.file, *model, p + ".model",
        fmt::format("expected one of: {}; found {}", fmt::join(models, ", "), model->Describe()));
  }
  return &imu;
}

Status ReadKalibr(const YamlNode& root, int instance, Filling* f) {
  Result<const YamlNode*> imu_r =
      ChainImu(root, instance, {"accelerometers", "gyroscopes"}, "calibrated",
               {"calibrated", "scale-misalignment", "scale-misalignment-size-effect"}, f);
  if (!imu_r.ok()) return imu_r.error();
  const YamlNode& imu = *imu_r.value();
  const std::string p = fmt::format("imu{}", instance);
  for (size_t i = 0; i < f->out.values.size(); ++i) {
    // Identity M and C, zero A: Kalibr's `calibrated` model.
    const std::string& n = f->out.values[i].name;
    const bool diag = n[n.size() - 2] == n[n.size() - 5];
    f->out.values[i].value = diag && n.find(".A[") == std::string::npos ? 1.0 : 0.0;
  }
  if (f->out.model == "calibrated") {
    f->out.notes.push_back("model calibrated: Kalibr takes the IMU as calibrated (no intrinsics)");
    return {};
  }
  const YamlNode* acc = imu.Find("accelerometers");
  const YamlNode* gyr = imu.Find("gyroscopes");
  if (acc == nullptr || gyr == nullptr) {
    return YamlError(f->out.file, imu, p + (acc == nullptr ? ".accelerometers" : ".gyroscopes"),
                     fmt::format("missing (the model {} carries them)", f->out.model));
  }
  if (Status s = CheckKeys(*acc, p + ".accelerometers", {"M", "rx_i", "ry_i", "rz_i"}, f->out.file);
      !s.ok()) {
    return s;
  }
  if (Status s = CheckKeys(*gyr, p + ".gyroscopes", {"M", "A", "C_gyro_i"}, f->out.file); !s.ok()) {
    return s;
  }
  if (acc->Find("rx_i") != nullptr) {
    f->out.notes.push_back(
        "accelerometers rx_i, ry_i, rz_i (size effect lever arms): metro has "
        "no size-effect term");
  }
  if (Status s = RequireMatrix(*acc, "M", p + ".accelerometers", f); !s.ok()) return s;
  if (Status s = RequireMatrix(*gyr, "M", p + ".gyroscopes", f); !s.ok()) return s;
  if (Status s = RequireMatrix(*gyr, "A", p + ".gyroscopes", f); !s.ok()) return s;
  return RequireMatrix(*gyr, "C_gyro_i", p + ".gyroscopes", f, true);
}

Status ReadOpenVins(const YamlNode& root, int instance, Filling* f) {
  Result<const YamlNode*> imu_r =
      ChainImu(root, instance, {"Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"}, "kalibr",
               {"calibrated", "kalibr", "rpng"}, f);
  if (!imu_r.ok()) return imu_r.error();
  const YamlNode& imu = *imu_r.value();
  const std::string p = fmt::format("imu{}", instance);
  // VioManagerOptions.h requires all five (parse_external with required = true).
  for (const char* k : {"Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"}) {
    const bool rotation = k[0] == 'R';
    if (Status s = RequireMatrix(imu, k, p, f, rotation); !s.ok()) return s;
  }
  return {};
}

Error JsonErrorAt(const JsonDocument& doc, const std::vector<JsonPathStep>& path,
                  const std::string& where, const std::string& message) {
  const auto [line, column] = doc.LineColumnOf(path);
  return MakeError(doc.file(), line, column, fmt::format("{}: {}", where, message));
}

// Unknown members of a JSON object refused with the ones expected.
Status CheckJsonKeys(const JsonCursor& j, const JsonDocument& doc,
                     const std::vector<JsonPathStep>& path, const std::set<std::string>& known) {
  if (!j.IsObject()) {
    j.Fail("an object");
    return j.error();
  }
  for (const std::string& k : j.Keys()) {
    if (known.count(k) == 0) {
      std::vector<JsonPathStep> at = path;
      at.emplace_back(k);
      return JsonErrorAt(
          doc, at, j.Path().empty() ? k : j.Path() + "." + k,
          fmt::format("unknown key (nearest: {}); expected one of: {}",
                      Nearest(k, {known.begin(), known.end()}), fmt::join(known, ", ")));
    }
  }
  return {};
}

// `n` numbers of a JSON array into the layout names `name[first..]`.
Status ReadJsonArray(const JsonCursor& j, const JsonDocument& doc,
                     const std::vector<JsonPathStep>& path, const std::string& name, size_t n,
                     Filling* f) {
  if (!j.IsArray() || j.Size() != n) {
    j.Fail(fmt::format("an array of {} numbers", n));
    return j.error();
  }
  for (size_t i = 0; i < n; ++i) {
    const double v = j[i].Number();
    if (!j.ok()) return j.error();
    std::vector<JsonPathStep> at = path;
    at.emplace_back(i);
    const auto [line, column] = doc.LineColumnOf(at);
    f->Set(fmt::format("{}[{}]", name, i), v, line, column);
  }
  return {};
}

Status ReadBasalt(const JsonDocument& doc, Filling* f) {
  const JsonCursor root(doc);
  if (Status s = CheckJsonKeys(root, doc, {}, {"value0", "metro_convention"}); !s.ok()) return s;
  const JsonCursor v = root["value0"];
  const std::set<std::string> known = {
      "T_imu_cam",          "intrinsics",           "resolution",
      "vignette",           "calib_accel_bias",     "calib_gyro_bias",
      "imu_update_rate",    "accel_noise_std",      "gyro_noise_std",
      "accel_bias_std",     "gyro_bias_std",        "T_mocap_world",
      "T_imu_marker",       "mocap_time_offset_ns", "mocap_to_imu_offset_ns",
      "cam_time_offset_ns", "view_offset"};
  if (Status s = CheckJsonKeys(v, doc, {"value0"}, known); !s.ok()) return s;
  if (Status s = ReadJsonArray(v["calib_accel_bias"], doc, {"value0", "calib_accel_bias"},
                               "value0.calib_accel_bias", 9, f);
      !s.ok()) {
    return s;
  }
  return ReadJsonArray(v["calib_gyro_bias"], doc, {"value0", "calib_gyro_bias"},
                       "value0.calib_gyro_bias", 12, f);
}

Status ReadRealSense(const JsonDocument& doc, int instance, Filling* f) {
  const JsonCursor root(doc);
  if (Status s = CheckJsonKeys(root, doc, {},
                               {"device_type", "imus", "metro_convention", "calibration_version",
                                "device_id", "cameras", "depths"});
      !s.ok()) {
    return s;
  }
  const JsonCursor imus = root["imus"];
  const size_t i = static_cast<size_t>(instance);
  if (!imus.IsArray() || imus.Size() <= i) {
    imus.Fail(fmt::format("an array with imu {} (give --instance)", instance));
    return imus.error();
  }
  const std::vector<JsonPathStep> ip = {std::string("imus"), i};
  if (Status s = CheckJsonKeys(imus[i], doc, ip,
                               {"accelerometer", "gyroscope", "extrinsics", "id", "name"});
      !s.ok()) {
    return s;
  }
  for (const char* sensor : {"accelerometer", "gyroscope"}) {
    std::vector<JsonPathStep> sp = ip;
    sp.emplace_back(std::string(sensor));
    const JsonCursor sj = imus[i][sensor];
    if (Status s = CheckJsonKeys(
            sj, doc, sp,
            {"scale_and_alignment", "bias", "bias_variance", "noise_variance", "decimate_by"});
        !s.ok()) {
      return s;
    }
    const std::string base = fmt::format("imus[{}].{}", instance, sensor);
    for (const auto& [key, n] :
         {std::pair<const char*, size_t>{"scale_and_alignment", 9}, {"bias", 3}}) {
      std::vector<JsonPathStep> kp = sp;
      kp.emplace_back(std::string(key));
      if (Status s = ReadJsonArray(sj[key], doc, kp, base + "." + key, n, f); !s.ok()) return s;
    }
  }
  return {};
}

// PX4 (QGroundControl .params "1 1 NAME VALUE TYPE", or `param set NAME VALUE`) and ArduPilot
// (.param "NAME,VALUE" or MAVProxy's "NAME VALUE") lines; other parameters of a dump are
// skipped, the layout's are required (the gyroscope's three offsets may be absent together).
Status ReadParameters(std::string_view text, Filling* f) {
  int64_t line = 0;
  size_t pos = 0;
  while (pos <= text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    std::string l(text.substr(pos, end - pos));
    pos = end + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    std::vector<std::pair<std::string, int64_t>> tok;  // token, 1-based column
    for (size_t c = 0; c < l.size();) {
      if (l[c] == ' ' || l[c] == '\t' || l[c] == ',') {
        ++c;
        continue;
      }
      const size_t b = c;
      while (c < l.size() && l[c] != ' ' && l[c] != '\t' && l[c] != ',') ++c;
      tok.emplace_back(l.substr(b, c - b), static_cast<int64_t>(b) + 1);
    }
    if (tok.empty() || tok[0].first[0] == '#') continue;
    size_t name_at = 0;
    if (tok.size() >= 4 && tok[0].first == "param" && tok[1].first == "set") {
      name_at = 2;
    } else if (tok.size() == 5) {
      name_at = 2;
    } else if (tok.size() != 2) {
      return MakeError(f->out.file, line, tok[0].second,
                       "expected `NAME,VALUE` (ArduPilot), `1 1 NAME VALUE TYPE` (QGroundControl) "
                       "or `param set NAME VALUE` (PX4)");
    }
    const auto& [name, name_col] = tok[name_at];
    const auto& [value, col] = tok[name_at + 1];
    if (f->index.count(name) == 0) continue;
    if (f->out.present[f->index.at(name)]) {
      return MakeError(f->out.file, line, name_col, fmt::format("{}: a duplicate parameter", name));
    }
    char* stop = nullptr;
    const double v = std::strtod(value.c_str(), &stop);
    if (stop != value.c_str() + value.size() || !std::isfinite(v)) {
      return MakeError(f->out.file, line, col,
                       fmt::format("{}: expected a number, found \"{}\"", name, value));
    }
    f->Set(name, v, line, col);
  }
  const size_t n = f->out.values.size();
  const bool gyro_any = f->out.present[6] || f->out.present[7] || f->out.present[8];
  for (size_t i = 0; i < n; ++i) {
    if (f->out.present[i] || (i >= 6 && !gyro_any)) continue;
    return MakeError(f->out.file, 1, 1,
                     fmt::format("missing parameter {} (expected the {} of instance; see "
                                 "docs/calibration-interchange.md)",
                                 f->out.values[i].name,
                                 i < 3   ? "accelerometer offsets"
                                 : i < 6 ? "accelerometer scales"
                                         : "gyroscope offsets"));
  }
  if (!gyro_any) f->out.notes.push_back("no gyroscope offsets: accelerometer only");
  return {};
}

}  // namespace

Result<InterchangeFile> ReadInterchangeFile(std::string_view text,
                                            const InterchangeReadOptions& options,
                                            const std::string& file) {
  Filling f(options.format, options.instance, file);
  Status s;
  switch (options.format) {
    case InterchangeFormat::kKalibr:
    case InterchangeFormat::kOpenVins: {
      Result<YamlNode> root = ParseYaml(text, file);
      if (!root.ok()) return root.error();
      s = options.format == InterchangeFormat::kKalibr
              ? ReadKalibr(root.value(), options.instance, &f)
              : ReadOpenVins(root.value(), options.instance, &f);
      break;
    }
    case InterchangeFormat::kBasalt:
    case InterchangeFormat::kRealSense: {
      Result<JsonDocument> doc = JsonDocument::Parse(std::string(text), file);
      if (!doc.ok()) return doc.error();
      s = options.format == InterchangeFormat::kBasalt
              ? ReadBasalt(doc.value(), &f)
              : ReadRealSense(doc.value(), options.instance, &f);
      break;
    }
    case InterchangeFormat::kPx4:
    case InterchangeFormat::kArduPilot:
      s = ReadParameters(text, &f);
      break;
  }
  if (!s.ok()) return s.error();
  f.out.positions = std::move(f.positions);
  f.out.sha256 = Sha256Hex(text);
  return std::move(f.out);
}

}  // namespace metro
