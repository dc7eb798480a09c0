// Private: the parameter blocks of the calibration problem, in the one order everything uses.
//
//   block  0 accel b(3)   1 accel k(3)   2 accel t(3)   3 accel b1(3)
//          4 gyro  b(3)   5 gyro  k(3)   6 gyro  t(6)   7 gyro  b1(3)
//
// This is the order of the blocks a residual takes (residuals.hpp; the rotation residual takes
// all 8), of the columns of a Jacobian over a sensor's free blocks, and of FreeNames (the rows
// of the covariance in calibration.json, imu_model.hpp): within a sensor the roles bias, scale,
// misalignment, bias_per_c, each block present when the model frees it.
// Identity (the default values): b = 0, k = 1, t = 0, b1 = 0.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "metro/calibration/imu_model.hpp"

namespace metro::calibration_internal {

class ParameterBlocks {
 public:
  // A block of one sensor.
  enum Role : int { kBias = 0, kScale = 1, kMisalignment = 2, kBiasPerC = 3 };
  static constexpr int kRoleCount = 4;

  enum Block : int {
    kAccelBias = 0,
    kAccelScale = 1,
    kAccelMisalignment = 2,
    kAccelBiasPerC = 3,
    kGyroBias = 4,
    kGyroScale = 5,
    kGyroMisalignment = 6,
    kGyroBiasPerC = 7,
  };
  static constexpr int kBlockCount = 8;

  // Sizes and offsets (into the parameters of all 8 blocks) in Block order.
  static constexpr std::array<int, kBlockCount> kSize = {3, 3, 3, 3, 3, 3, 6, 3};
  static constexpr std::array<int, kBlockCount> kOffset = {0, 3, 6, 9, 12, 15, 18, 24};
  static constexpr int kTotal = 27;
  static constexpr int kAccelTotal = 12;  // Parameters of blocks 0-3.
  static constexpr int kGyroTotal = 15;   // Parameters of blocks 4-7.

  static constexpr Block BlockOf(ImuSensor sensor, Role role) {
    return static_cast<Block>((sensor == ImuSensor::kAccel ? 0 : kRoleCount) + role);
  }
  static constexpr int Size(ImuSensor sensor, Role role) { return kSize[BlockOf(sensor, role)]; }

  // Whether a model frees a role: the bias always; the scale unless kBias; the misalignment
  // with kFull; the temperature term b1 when fitted.
  static constexpr bool IsFree(Role role, ModelKind kind, bool temperature) {
    switch (role) {
      case kBias:
        return true;
      case kScale:
        return kind != ModelKind::kBias;
      case kMisalignment:
        return kind == ModelKind::kFull;
      case kBiasPerC:
        return temperature;
    }
    return false;
  }

  // The number of free parameters of a sensor.
  static int FreeCount(ImuSensor sensor, ModelKind kind, bool temperature) {
    int n = 0;
    for (int r = 0; r < kRoleCount; ++r) {
      if (IsFree(static_cast<Role>(r), kind, temperature)) n += Size(sensor, static_cast<Role>(r));
    }
    return n;
  }

  // The free parameters' names in covariance order, e.g. accel full with temperature:
  // b_x b_y b_z k_x k_y k_z a_yz a_zy a_zx b1_x b1_y b1_z.
  static std::vector<std::string> FreeNames(ImuSensor sensor, ModelKind kind, bool temperature) {
    static const char* const kAccelNames[] = {"b_x",  "b_y",  "b_z",  "k_x",  "k_y",  "k_z",
                                              "a_yz", "a_zy", "a_zx", "b1_x", "b1_y", "b1_z"};
    static const char* const kGyroNames[] = {"b_x",  "b_y",  "b_z",  "k_x",  "k_y",
                                             "k_z",  "g_yz", "g_zy", "g_xz", "g_zx",
                                             "g_xy", "g_yx", "b1_x", "b1_y", "b1_z"};
    const char* const* names = sensor == ImuSensor::kAccel ? kAccelNames : kGyroNames;
    const int first = kOffset[BlockOf(sensor, kBias)];
    std::vector<std::string> out;
    for (int r = 0; r < kRoleCount; ++r) {
      const Role role = static_cast<Role>(r);
      if (!IsFree(role, kind, temperature)) continue;
      const int begin = kOffset[BlockOf(sensor, role)] - first;
      for (int i = begin; i < begin + Size(sensor, role); ++i) out.push_back(names[i]);
    }
    return out;
  }

  // Where a free role's parameters start in the free vector (FreeNames order); -1 if the
  // model holds the role.
  static int FreeOffset(ImuSensor sensor, ModelKind kind, bool temperature, Role role) {
    if (!IsFree(role, kind, temperature)) return -1;
    int n = 0;
    for (int r = 0; r < role; ++r) {
      if (IsFree(static_cast<Role>(r), kind, temperature)) n += Size(sensor, static_cast<Role>(r));
    }
    return n;
  }

  ParameterBlocks() {
    for (int b = 0; b < kBlockCount; ++b) {
      const double v = b == kAccelScale || b == kGyroScale ? 1.0 : 0.0;
      for (int i = 0; i < kSize[b]; ++i) values_[kOffset[b] + i] = v;
    }
  }

  double* operator[](Block b) { return values_ + kOffset[b]; }
  const double* operator[](Block b) const { return values_ + kOffset[b]; }
  double* Get(ImuSensor sensor, Role role) { return (*this)[BlockOf(sensor, role)]; }
  const double* Get(ImuSensor sensor, Role role) const { return (*this)[BlockOf(sensor, role)]; }

  // The 4 blocks of one sensor (b, k, t, b1), e.g. for the pose and table residuals.
  std::vector<double*> SensorBlocks(ImuSensor sensor) {
    std::vector<double*> out;
    for (int r = 0; r < kRoleCount; ++r) out.push_back(Get(sensor, static_cast<Role>(r)));
    return out;
  }
  // All 8 blocks in Block order (the rotation residual's parameters).
  std::vector<double*> All() {
    std::vector<double*> out;
    for (int b = 0; b < kBlockCount; ++b) out.push_back((*this)[static_cast<Block>(b)]);
    return out;
  }
  std::array<const double*, kBlockCount> AllConst() const {
    std::array<const double*, kBlockCount> out{};
    for (int b = 0; b < kBlockCount; ++b) out[b] = (*this)[static_cast<Block>(b)];
    return out;
  }

 private:
  // One array in Block order: Ceres's covariance orders blocks by address, so the blocks'
  // addresses increase in Block order.
  double values_[kTotal];
};

static_assert(ParameterBlocks::kOffset[ParameterBlocks::kBlockCount - 1] +
                      ParameterBlocks::kSize[ParameterBlocks::kBlockCount - 1] ==
                  ParameterBlocks::kTotal,
              "sizes and offsets agree");
static_assert(ParameterBlocks::kOffset[ParameterBlocks::kGyroBias] == ParameterBlocks::kAccelTotal,
              "the accelerometer's blocks come first");

}  // namespace metro::calibration_internal
