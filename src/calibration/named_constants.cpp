#include "metro/calibration/named_constants.hpp"

#include <algorithm>

namespace metro {
namespace {

const char* const kAxes[] = {"x", "y", "z"};
const char* const kAccelMisalignment[] = {"a_yz", "a_zy", "a_zx"};
const char* const kGyroMisalignment[] = {"g_yz", "g_zy", "g_xz", "g_zx", "g_xy", "g_yx"};

void AddSensor(const std::string& prefix, const SensorCalibration& c,
               std::vector<NamedConstant>* out) {
  const std::string in = CalibrationUnitText(c.model.input_unit);
  const std::string output = CalibrationUnitText(c.model.output_unit);
  const std::string k_unit = in == output ? std::string("1") : output + "/" + in;
  auto add = [&](const std::string& name, double value, double u, const std::string& unit) {
    NamedConstant n;
    n.name = prefix + "." + name;
    n.value = value;
    n.u = u;
    n.unit = unit;
    const auto it = std::find(c.parameter_names.begin(), c.parameter_names.end(), name);
    if (it != c.parameter_names.end()) {
      n.covariance_index = static_cast<int>(it - c.parameter_names.begin());
    }
    out->push_back(std::move(n));
  };
  for (int a = 0; a < 3; ++a) {
    add(std::string("b_") + kAxes[a], c.model.bias[a], c.bias_u[a], in);
  }
  for (int a = 0; a < 3; ++a) {
    add(std::string("k_") + kAxes[a], c.model.scale[a], c.scale_u[a], k_unit);
  }
  const bool accel = c.model.sensor == ImuSensor::kAccel;
  const size_t nm = accel ? 3 : 6;
  for (size_t i = 0; i < nm; ++i) {
    const double v = i < c.model.misalignment.size() ? c.model.misalignment[i] : 0.0;
    const double u = i < c.misalignment_u.size() ? c.misalignment_u[i] : 0.0;
    add(accel ? kAccelMisalignment[i] : kGyroMisalignment[i], v, u, "rad");
  }
  if (c.model.has_temperature) {
    for (int a = 0; a < 3; ++a) {
      add(std::string("b1_") + kAxes[a], c.model.bias_per_c[a], c.bias_per_c_u[a], in + "/K");
    }
  }
}

}  // namespace

std::string CalibrationUnitText(const std::string& symbol) {
  return symbol == "g" ? std::string("g_n") : symbol;
}

std::vector<NamedConstant> NamedConstants(const TagCalibration& tag) {
  std::vector<NamedConstant> out;
  if (tag.accel) AddSensor("accel", *tag.accel, &out);
  if (tag.gyro) AddSensor("gyro", *tag.gyro, &out);
  return out;
}

}  // namespace metro
