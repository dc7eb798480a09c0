#include "metro/calibration/autopilot_export.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <cmath>

#include "metro/calibration/calibration_io.hpp"

namespace metro {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr char kAxes[3] = {'X', 'Y', 'Z'};

// SI units per unit of a calibration's input or output (imu_model.hpp's units); nullopt for
// counts, which need the full-scale setting.
std::optional<double> UnitToSi(const std::string& unit) {
  if (unit == "g") return kStandardGravityMps2;
  if (unit == "m/s^2" || unit == "rad/s") return 1.0;
  if (unit == "deg/s") return kPi / 180.0;
  return std::nullopt;
}

// The nominal sensitivity of 16-bit counts at a full scale (g or deg/s), in SI per count: what
// an autopilot's driver multiplies the counts by.
double CountToSi(ImuSensor sensor, double full_scale) {
  return full_scale / 32768.0 * (sensor == ImuSensor::kAccel ? kStandardGravityMps2 : kPi / 180.0);
}

// The parameter names of one autopilot for a sensor and axis.
std::string ParameterName(AutopilotFormat format, ImuSensor sensor, int instance, bool scale,
                          int axis) {
  const bool accel = sensor == ImuSensor::kAccel;
  if (format == AutopilotFormat::kPx4) {
    return fmt::format("CAL_{}{}_{}{}", accel ? "ACC" : "GYRO", instance, kAxes[axis],
                       scale ? "SCALE" : "OFF");
  }
  const std::string index = instance == 0 ? "" : std::to_string(instance + 1);
  return fmt::format("INS_{}{}{}_{}", accel ? "ACC" : "GYR", index, scale ? "SCAL" : "OFFS",
                     kAxes[axis]);
}

// One parameter line: PX4's QGroundControl .params ("vehicle component name value type",
// type 9 = MAV_PARAM_TYPE_REAL32, 6 = INT32), ArduPilot's .param ("NAME,VALUE"). 17
// significant digits: the value reads back as the double written.
std::string ParameterLine(AutopilotFormat format, const std::string& name, double value,
                          bool integer = false) {
  if (format == AutopilotFormat::kPx4) {
    return integer ? fmt::format("1\t1\t{}\t{}\t6\n", name, static_cast<int64_t>(value))
                   : fmt::format("1\t1\t{}\t{:.17g}\t9\n", name, value);
  }
  return fmt::format("{},{:.17g}\n", name, value);
}

std::string SensorBlock(AutopilotFormat format, int instance, const AutopilotSensorForm& f,
                        const std::optional<int64_t>& px4_device_id) {
  const bool accel = f.sensor == ImuSensor::kAccel;
  std::string out = fmt::format(
      "# {}: corrected [{}] = (data - offset){} ; data = the driver's {} (counts x nominal "
      "sensitivity)\n",
      ImuSensorLongName(f.sensor), f.si_unit, f.scale_held ? " .* scale" : "", f.si_unit);
  for (int a = 0; a < 3; ++a) {
    out += fmt::format("#   {} offset {:.9g} {} (u {:.2g}, k = 1)", kAxes[a], f.offset(a),
                       f.si_unit, f.offset_u(a));
    if (f.scale_held) out += fmt::format(", scale {:.9g} (u {:.2g})", f.scale(a), f.scale_u(a));
    out += "\n";
  }
  for (const std::string& n : f.not_held) out += "#   NOT HELD: " + n + "\n";
  if (format == AutopilotFormat::kPx4) {
    const std::string id = fmt::format("CAL_{}{}_ID", accel ? "ACC" : "GYRO", instance);
    if (px4_device_id) {
      out += ParameterLine(format, id, static_cast<double>(*px4_device_id), true);
    } else {
      out += fmt::format(
          "#   {} not written: PX4 applies these values only to the device whose ID "
          "it holds (give --px4-{}-device-id)\n",
          id, accel ? "accel" : "gyro");
    }
  }
  for (int a = 0; a < 3; ++a) {
    out += ParameterLine(format, ParameterName(format, f.sensor, instance, false, a), f.offset(a));
  }
  if (f.scale_held) {
    for (int a = 0; a < 3; ++a) {
      out += ParameterLine(format, ParameterName(format, f.sensor, instance, true, a), f.scale(a));
    }
  }
  return out;
}

}  // namespace

const char* AutopilotFormatName(AutopilotFormat format) {
  return format == AutopilotFormat::kPx4 ? "px4" : "ardupilot";
}

std::optional<AutopilotFormat> ParseAutopilotFormat(std::string_view name) {
  if (name == "px4") return AutopilotFormat::kPx4;
  if (name == "ardupilot") return AutopilotFormat::kArduPilot;
  return std::nullopt;
}

Eigen::Vector3d AutopilotSensorForm::Correct(const Eigen::Vector3d& data_si) const {
  const Eigen::Vector3d d = data_si - offset;
  return scale_held ? Eigen::Vector3d(d.cwiseProduct(scale)) : d;
}

Result<AutopilotSensorForm> AutopilotForm(const SensorCalibration& calibration) {
  const SensorModel& m = calibration.model;
  AutopilotSensorForm f;
  f.sensor = m.sensor;
  f.si_unit = m.sensor == ImuSensor::kAccel ? "m/s^2" : "rad/s";
  const std::optional<double> out = UnitToSi(m.output_unit);
  std::optional<double> in = UnitToSi(m.input_unit);
  if (!in && m.input_unit == "LSB" && calibration.full_scale) {
    in = CountToSi(m.sensor, *calibration.full_scale);
  }
  if (!out || !in) {
    return MakeError(fmt::format(
        "{}: input unit '{}' (output '{}'): expected g, m/s^2, deg/s, rad/s, or LSB with the "
        "full_scale calibration.json records for counts",
        ImuSensorLongName(m.sensor), m.input_unit, m.output_unit));
  }
  f.input_to_si = *in;
  f.output_to_si = *out;
  f.offset = *in * m.bias;
  f.offset_u = *in * calibration.bias_u;
  f.scale = (*out / *in) * m.scale;
  f.scale_u = (*out / *in) * calibration.scale_u;
  f.scale_held = m.sensor == ImuSensor::kAccel;
  if (!f.scale_held) {
    const double worst = (f.scale.array() - 1.0).abs().maxCoeff();
    if (worst > 0.0) {
      f.not_held.push_back(fmt::format(
          "the gyroscope's scale factors {:.6f} {:.6f} {:.6f} (an error of up to {:.3g} % of the "
          "rate; both autopilots hold a gyroscope offset only)",
          f.scale(0), f.scale(1), f.scale(2), 100.0 * worst));
    }
  }
  if (!m.misalignment.empty()) {
    const Eigen::Matrix3d t = MisalignmentMatrix(m.sensor, m.misalignment.data());
    const double norm =
        Eigen::JacobiSVD<Eigen::Matrix3d>(t - Eigen::Matrix3d::Identity()).singularValues()(0);
    if (norm > 0.0) {
      f.not_held.push_back(fmt::format(
          "the misalignment (cross-axis) terms: up to {:.3g} % of the corrected vector (the "
          "spectral norm of T - I)",
          100.0 * norm));
    }
  }
  if (m.has_temperature && m.bias_per_c.cwiseAbs().maxCoeff() > 0.0) {
    const Eigen::Vector3d b1 = *in * m.bias_per_c;
    f.not_held.push_back(fmt::format(
        "the bias temperature term {:.3g} {:.3g} {:.3g} {}/degC about {:g} degC (the offset "
        "written is the bias at {:g} degC)",
        b1(0), b1(1), b1(2), f.si_unit, m.t_ref_c, m.t_ref_c));
  }
  return f;
}

Result<AutopilotExport> ExportAutopilotParameters(const Calibration& calibration,
                                                  const AutopilotExportOptions& options) {
  const int max_instance = options.format == AutopilotFormat::kPx4 ? 3 : 2;
  if (options.instance < 0 || options.instance > max_instance) {
    return MakeError(fmt::format("--instance {}: {} has IMU instances 0..{}", options.instance,
                                 AutopilotFormatName(options.format), max_instance));
  }
  const TagCalibration* tag = calibration.FindTag(options.sensor);
  if (tag == nullptr) return NoSensorError(calibration, options.sensor);
  AutopilotExport out;
  out.text = fmt::format(
      "# metro calibration of tag {} ({}), {} parameters for IMU instance {}\n"
      "# calibrated {}, {}; values with their standard uncertainty (k = 1) in the comments\n",
      options.sensor, calibration.source_file.empty() ? "calibration" : calibration.source_file,
      AutopilotFormatName(options.format), options.instance, calibration.date_utc,
      calibration.tool_version);
  if (options.format == AutopilotFormat::kPx4) {
    out.text +=
        "# Onboard parameters (QGroundControl .params)\n# Vehicle-Id\tComponent-Id\tName\t"
        "Value\tType\n";
  }
  for (const auto* sensor : {&tag->accel, &tag->gyro}) {
    if (!sensor->has_value()) continue;
    const SensorCalibration& c = **sensor;
    if (c.model_check && c.model_check->model_rejected) {
      return CalibrationErrorAt(
          calibration, CalibrationSensorPath(calibration, options.sensor, c.model.sensor),
          fmt::format("the {} model is model_rejected ({}): its constants are not exported",
                      ImuSensorLongName(c.model.sensor), c.model_check->reason));
    }
    Result<AutopilotSensorForm> form = AutopilotForm(c);
    if (!form.ok()) return form.error();
    const bool accel = c.model.sensor == ImuSensor::kAccel;
    out.text += SensorBlock(options.format, options.instance, form.value(),
                            accel ? options.px4_accel_device_id : options.px4_gyro_device_id);
    for (const std::string& n : form.value().not_held) {
      out.warnings.push_back(fmt::format("sensor {} {}: {} cannot hold {}", options.sensor,
                                         ImuSensorLongName(c.model.sensor),
                                         AutopilotFormatName(options.format), n));
    }
  }
  return out;
}

}  // namespace metro
