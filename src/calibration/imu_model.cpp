#include "metro/calibration/imu_model.hpp"

#include <Eigen/LU>
#include <cmath>

#include "metro/core/check.hpp"

namespace metro {

const char* ModelKindName(ModelKind kind) {
  switch (kind) {
    case ModelKind::kBias:
      return "bias";
    case ModelKind::kScale:
      return "scale";
    case ModelKind::kFull:
      return "full";
  }
  return "full";
}

std::optional<ModelKind> ParseModelKind(std::string_view name) {
  if (name == "bias") return ModelKind::kBias;
  if (name == "scale") return ModelKind::kScale;
  if (name == "full") return ModelKind::kFull;
  return std::nullopt;
}

const char* ImuSensorName(ImuSensor sensor) {
  return sensor == ImuSensor::kAccel ? "accel" : "gyro";
}

int MisalignmentCount(ImuSensor sensor) { return sensor == ImuSensor::kAccel ? 3 : 6; }

Eigen::Matrix3d MisalignmentMatrix(ImuSensor sensor, const double* m) {
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  if (sensor == ImuSensor::kAccel) {
    t(0, 1) = -m[0];
    t(0, 2) = m[1];
    t(1, 2) = -m[2];
  } else {
    t(0, 1) = -m[0];
    t(0, 2) = m[1];
    t(1, 0) = m[2];
    t(1, 2) = -m[3];
    t(2, 0) = -m[4];
    t(2, 1) = m[5];
  }
  return t;
}

Eigen::Matrix3d SensorModel::Matrix() const {
  Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
  if (!misalignment.empty()) {
    METRO_CHECK(static_cast<int>(misalignment.size()) == MisalignmentCount(sensor));
    t = MisalignmentMatrix(sensor, misalignment.data());
  }
  return t * scale.asDiagonal();
}

Eigen::Vector3d SensorModel::BiasAt(double temp_c) const {
  if (!has_temperature) return bias;
  return bias + bias_per_c * (temp_c - t_ref_c);
}

Eigen::Vector3d SensorModel::Apply(const Eigen::Vector3d& raw, double temp_c) const {
  return Matrix() * (raw - BiasAt(temp_c));
}

Eigen::Vector3d SensorModel::Invert(const Eigen::Vector3d& calibrated, double temp_c) const {
  return Matrix().partialPivLu().solve(calibrated) + BiasAt(temp_c);
}

SensorKind ColumnSensorKind(ImuSensor sensor) {
  return sensor == ImuSensor::kAccel ? SensorKind::kAccelerometer : SensorKind::kGyroscope;
}

const char* ImuSensorLongName(ImuSensor sensor) {
  return sensor == ImuSensor::kAccel ? "accelerometer" : "gyroscope";
}

const Unit& OutputUnit(ImuSensor sensor) {
  const Unit* unit = UnitBySymbol(sensor == ImuSensor::kAccel ? "g" : "deg/s");
  METRO_CHECK(unit != nullptr);
  return *unit;
}

const Unit* InputUnit(ImuSensor sensor, std::string_view input_unit) {
  const Unit* unit = UnitBySymbol(input_unit);
  for (const Unit* allowed : AxisUnits(ColumnSensorKind(sensor))) {
    if (unit != nullptr && allowed == unit) return unit;
  }
  return nullptr;
}

std::vector<std::string> InputColumns(ImuSensor sensor, std::string_view input_unit) {
  const Unit* unit = InputUnit(sensor, input_unit);
  if (unit == nullptr) return {};
  return FamilyColumns(ColumnSensorKind(sensor), unit);
}

std::optional<double> NominalScale(ImuSensor sensor, std::string_view input_unit,
                                   double full_scale) {
  const Unit* unit = InputUnit(sensor, input_unit);
  if (unit == nullptr) return std::nullopt;
  if (unit->dimension != Dimension::kRawCount) return ConversionFactor(*unit, OutputUnit(sensor));
  // Raw counts have no SI scale: the sensitivity comes from the datasheet.
  if (!(full_scale > 0)) return std::nullopt;
  if (sensor == ImuSensor::kAccel) {
    return full_scale / 32768.0;  // 16384 LSB/g at +-2 g (datasheet table 6.2).
  }
  // Datasheet table 6.1 sensitivities (131 LSB/(deg/s) at +-250, not 32768/250).
  if (full_scale == 250.0) return 1.0 / 131.0;
  if (full_scale == 500.0) return 1.0 / 65.5;
  if (full_scale == 1000.0) return 1.0 / 32.8;
  if (full_scale == 2000.0) return 1.0 / 16.4;
  return full_scale / 32768.0;
}

}  // namespace metro
