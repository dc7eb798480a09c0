// Derivatives of the residual blocks against central differences.
#include "calibration/residuals.hpp"

#include <ceres/cost_function.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace metro {
namespace {

namespace ci = calibration_internal;

// Compares every Jacobian block of `cost` at `params` with central differences
// (h = 1e-6 relative); returns the largest relative discrepancy.
double MaxJacobianError(const ceres::CostFunction& cost, std::vector<std::vector<double>> params) {
  const int nr = cost.num_residuals();
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  std::vector<double*> ptr;
  for (auto& p : params) ptr.push_back(p.data());
  std::vector<std::vector<double>> jac(sizes.size());
  std::vector<double*> jptr;
  for (size_t b = 0; b < sizes.size(); ++b) {
    jac[b].resize(static_cast<size_t>(nr * sizes[b]));
    jptr.push_back(jac[b].data());
  }
  std::vector<double> r(static_cast<size_t>(nr)), rp(r), rm(r);
  REQUIRE(cost.Evaluate(ptr.data(), r.data(), jptr.data()));
  double worst = 0;
  for (size_t b = 0; b < sizes.size(); ++b) {
    for (int c = 0; c < sizes[b]; ++c) {
      double& x = params[b][static_cast<size_t>(c)];
      const double x0 = x;
      const double h = x0 != 0 ? 1e-6 * std::abs(x0) : 1e-9;
      x = x0 + h;
      REQUIRE(cost.Evaluate(ptr.data(), rp.data(), nullptr));
      x = x0 - h;
      REQUIRE(cost.Evaluate(ptr.data(), rm.data(), nullptr));
      x = x0;
      for (int i = 0; i < nr; ++i) {
        const double numeric = (rp[static_cast<size_t>(i)] - rm[static_cast<size_t>(i)]) / (2 * h);
        const double analytic = jac[b][static_cast<size_t>(i * sizes[b] + c)];
        const double scale = std::max(1e-3, std::abs(numeric));
        worst = std::max(worst, std::abs(analytic - numeric) / scale);
      }
    }
  }
  return worst;
}

TEST_CASE("Accelerometer norm residual derivatives match central differences", "[calibration]") {
  std::unique_ptr<ceres::CostFunction> cost(
      ci::NewAccelNormCost(Eigen::Vector3d(9000, -12000, 3000), 2.5, 1.0, 3.0));
  const double k = 1.0 / 16384;
  CHECK(MaxJacobianError(
            *cost, {{100, -50, 20}, {k, k * 1.01, k * 0.99}, {0.01, -0.02, 0.005}, {1, 2, -1}}) <
        1e-5);
}

TEST_CASE("Gyroscope table residual derivatives match central differences", "[calibration]") {
  std::unique_ptr<ceres::CostFunction> cost(
      ci::NewGyroTableCost(Eigen::Vector3d(5000, -8000, 12000), -1.5, 90.0, 2.0));
  const double k = 1.0 / 131;
  CHECK(MaxJacobianError(*cost, {{100, -50, 20},
                                 {k, k * 1.01, k * 0.99},
                                 {0.01, -0.02, 0.005, 0.01, 0.003, -0.004},
                                 {1, 2, -1}}) < 1e-5);
}

TEST_CASE("Rotation residual chain-rule derivatives match central differences", "[calibration]") {
  ci::RotationData d;
  d.accel_start = Eigen::Vector3d(2000, -3000, 15000);
  d.accel_end = Eigen::Vector3d(-9000, 12000, 4000);
  d.dtemp_start_c = -0.5;
  d.dtemp_end_c = 0.7;
  d.weight = 5.0;
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 150; ++i) {
    // A rotation of about 100 deg/s on a varying axis, in raw counts.
    d.gyro.push_back(
        Eigen::Vector3d(13000 + 3000 * n(rng), -6000 + 3000 * n(rng), 4000 + 3000 * n(rng)));
    d.dt_s.push_back(0.01 + 0.0005 * n(rng));
    d.dtemp_c.push_back(-0.5 + 0.008 * i);
  }
  std::unique_ptr<ceres::CostFunction> cost(ci::NewRotationCost(d));
  const double ka = 1.0 / 16384, kg = 1.0 / 131;
  CHECK(MaxJacobianError(*cost, {{100, -50, 20},
                                 {ka, ka * 1.01, ka * 0.99},
                                 {0.01, -0.02, 0.005},
                                 {1, 2, -1},
                                 {300, -200, 150},
                                 {kg, kg * 1.02, kg * 0.98},
                                 {0.01, -0.02, 0.005, 0.01, 0.003, -0.004},
                                 {3, -2, 1}}) < 1e-5);
}

TEST_CASE("Rotation residual is zero for an exact rotation", "[calibration]") {
  // Identity calibration; gravity along +z turned by 90 deg about body x in 100 steps gives
  // gravity along ... R^T z with R = Rx(90 deg): R^T (0,0,1) = (0, 1, 0).
  ci::RotationData d;
  d.accel_start = Eigen::Vector3d(0, 0, 1);
  d.accel_end = Eigen::Vector3d(0, 1, 0);
  for (int i = 0; i < 100; ++i) {
    d.gyro.push_back(Eigen::Vector3d(90.0, 0, 0));  // deg/s for 1 s.
    d.dt_s.push_back(0.01);
    d.dtemp_c.push_back(0);
  }
  const double zero[6] = {0, 0, 0, 0, 0, 0}, one[3] = {1, 1, 1};
  const double* p[8] = {zero, one, zero, zero, zero, one, zero, zero};
  CHECK(ci::RotationResidual(d, p).norm() < 1e-12);
}

}  // namespace
}  // namespace metro
