// Private: the numbers of each interchange format (interchange.hpp) as functions of the two
// sensors' SI forms in the format's frame, and back, shared by the export and the import.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "metro/calibration/interchange.hpp"

namespace metro::interchange_internal {

// The accelerometer and gyroscope in one frame.
struct FramedForms {
  SiSensorForm accel;
  SiSensorForm gyro;
};

// The names and units of a format's numbers, in layout order (the file's own names).
std::vector<InterchangeValue> Layout(InterchangeFormat format, int instance);

// Whether the format holds a lower triangular accelerometer matrix (its frame is turned from
// metro's: kalibr, openvins, basalt).
bool LowerTriangularAccel(InterchangeFormat format);

// M = R L: R a rotation, L lower triangular with a positive diagonal. Precondition: det M > 0.
void RotationTimesLower(const Eigen::Matrix3d& m, Eigen::Matrix3d* r, Eigen::Matrix3d* l);
// M = Q U: Q a rotation, U upper triangular with a positive diagonal. Precondition: det M > 0.
void RotationTimesUpper(const Eigen::Matrix3d& m, Eigen::Matrix3d* q, Eigen::Matrix3d* u);

// The format's numbers (Layout order) from the forms in the format's frame.
Eigen::VectorXd ValuesFromForms(InterchangeFormat format, const FramedForms& forms);
// The forms in the format's frame from its numbers (`model`: openvins "rpng" or "kalibr").
FramedForms FormsFromValues(InterchangeFormat format, const Eigen::VectorXd& values);

// Central-difference Jacobian of f at x, step h_i per coordinate (JCGM 101:2008 / 102:2011
// numerical sensitivity coefficients; truncation error O(h^2)).
Eigen::MatrixXd NumericJacobian(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f,
                                const Eigen::VectorXd& x, const Eigen::VectorXd& h);

// A named free parameter of calibration.json's `parameters` ("b_x", "k_z", "a_zy", "g_xz",
// "b1_y") in a SensorModel.
void SetParameter(const std::string& name, double value, SensorModel* m);
double GetParameter(const std::string& name, const SensorModel& m);

// The rotation angle of R [rad].
double RotationAngle(const Eigen::Matrix3d& r);

}  // namespace metro::interchange_internal
