#include "metro/sim/raw_tag.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <pcg_random.hpp>
#include <random>

#include "metro/core/check.hpp"

namespace metro {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

bool RawTagOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* m) {
    if (why != nullptr) *why = m;
    return false;
  };
  if (!(rate_hz > 0)) return fail("rate_hz must be > 0");
  if (!(accel_fs_g > 0) || !(gyro_fs_dps > 0)) return fail("full-scale settings must be > 0");
  if (!(accel_noise_ug_rthz >= 0) || !(gyro_noise_dps_rthz >= 0) || !(bandwidth_hz > 0)) {
    return fail("noise densities must be >= 0 and bandwidth_hz > 0");
  }
  if (!(start_up.norm() > 0)) return fail("start_up must not be zero");
  return true;
}

struct SimulatedRawTag::Impl {
  RawTagOptions o;
  ImuTruth truth;
  pcg64 rng;
  std::normal_distribution<double> normal{0.0, 1.0};
  Eigen::Matrix3d r_wb = Eigen::Matrix3d::Identity();  // world_from_body
  size_t k = 0;                                        // Next sample index.

  explicit Impl(const RawTagOptions& options)
      : o(options),
        truth(o.random_truth ? DrawImuTruth(o.seed, o.accel_fs_g, o.gyro_fs_dps, false,
                                            o.accel_cross_axis, o.gyro_cross_axis)
                             : o.truth),
        rng(o.seed ^ 0x7f4a7c159e3779b9ULL) {
    r_wb = Eigen::Quaterniond::FromTwoVectors(o.start_up.normalized(), Eigen::Vector3d::UnitZ())
               .toRotationMatrix();
  }

  Eigen::Vector3d Noise(double sd) {
    const double x = normal(rng), y = normal(rng), z = normal(rng);
    return Eigen::Vector3d(x, y, z) * sd;
  }

  // Samples over duration_s: orientation(tau) and body linear acceleration(tau) [g].
  void Run(double duration_s, const std::function<Eigen::Matrix3d(double)>& orientation,
           const std::function<Eigen::Vector3d(double)>& linear_g, std::vector<RawTagSample>* out) {
    const double dt = 1.0 / o.rate_hz;
    const double t0 = static_cast<double>(k) * dt;
    const auto n = static_cast<size_t>(std::llround(duration_s * o.rate_hz));
    const double accel_sd_g = o.accel_noise_ug_rthz * 1e-6 * std::sqrt(o.bandwidth_hz);
    const double gyro_sd_dps = o.gyro_noise_dps_rthz * std::sqrt(o.bandwidth_hz);
    Eigen::Matrix3d prev = r_wb;
    for (size_t i = 0; i < n; ++i, ++k) {
      const double tau = static_cast<double>(i + 1) * dt;
      const Eigen::Matrix3d r = orientation(tau);
      const Eigen::AngleAxisd step(prev.transpose() * r);
      const Eigen::Vector3d w_dps = step.axis() * step.angle() / dt * 180.0 / kPi;
      prev = r;
      const Eigen::Vector3d f_g = r.transpose() * Eigen::Vector3d::UnitZ() + linear_g(tau);
      RawTagSample s;
      s.t_s = t0 + tau - dt;
      const Eigen::Vector3d ra =
          TruthToCounts(truth.accel, f_g + Noise(accel_sd_g), 0.0, &s.saturated);
      const Eigen::Vector3d rg =
          TruthToCounts(truth.gyro, w_dps + Noise(gyro_sd_dps), 0.0, &s.saturated);
      for (int a = 0; a < 3; ++a) {
        s.counts[a] = static_cast<int32_t>(ra[a]);
        s.counts[3 + a] = static_cast<int32_t>(rg[a]);
      }
      out->push_back(s);
    }
    r_wb = prev;
  }

  // A minimum-jerk turn from r_wb to `target` about one body axis (the calibration simulator's
  // hand rotation).
  void TurnTo(const Eigen::Matrix3d& target, double duration_s, std::vector<RawTagSample>* out) {
    const Eigen::Matrix3d r0 = r_wb;
    const Eigen::AngleAxisd rel(r0.transpose() * target);
    const Eigen::Vector3d axis = rel.axis();
    const double angle = rel.angle();
    Run(
        duration_s,
        [&](double tau) {
          const double s = std::clamp(tau / duration_s, 0.0, 1.0);
          const double th = angle * s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
          return Eigen::Matrix3d(r0 * Eigen::AngleAxisd(th, axis).toRotationMatrix());
        },
        [](double) { return Eigen::Vector3d::Zero(); }, out);
  }

  Eigen::Matrix3d Pose(const Eigen::Vector3d& up_body) {
    std::uniform_real_distribution<double> heading(-kPi, kPi);
    const Eigen::Matrix3d align =
        Eigen::Quaterniond::FromTwoVectors(up_body.normalized(), Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    return Eigen::AngleAxisd(heading(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * align;
  }
};

SimulatedRawTag::SimulatedRawTag(const RawTagOptions& options)
    : impl_(std::make_unique<Impl>(options)) {
  std::string why;
  METRO_CHECK(options.IsValid(&why));
}

SimulatedRawTag::~SimulatedRawTag() = default;

const ImuTruth& SimulatedRawTag::Truth() const { return impl_->truth; }

Eigen::Vector3d SimulatedRawTag::UpBody() const {
  return impl_->r_wb.transpose() * Eigen::Vector3d::UnitZ();
}

double SimulatedRawTag::TimeS() const { return static_cast<double>(impl_->k) / impl_->o.rate_hz; }

void SimulatedRawTag::Hold(double duration_s, std::vector<RawTagSample>* out) {
  const Eigen::Matrix3d r = impl_->r_wb;
  impl_->Run(
      duration_s, [&](double) { return r; }, [](double) { return Eigen::Vector3d::Zero(); }, out);
}

void SimulatedRawTag::Move(const Eigen::Vector3d& up_body, double duration_s,
                           std::vector<RawTagSample>* out) {
  impl_->TurnTo(impl_->Pose(up_body), duration_s, out);
}

void SimulatedRawTag::Knock(double peak_g, std::vector<RawTagSample>* out) {
  constexpr double kKnockS = 0.08;
  const Eigen::Vector3d dir = impl_->Noise(1.0).normalized();
  const Eigen::Vector3d axis = impl_->Noise(1.0).normalized();
  const Eigen::Matrix3d r0 = impl_->r_wb;
  impl_->Run(
      kKnockS,
      [&](double tau) {
        const double th = kPi / 180.0 * std::sin(kPi * std::min(tau / kKnockS, 1.0));
        return Eigen::Matrix3d(r0 * Eigen::AngleAxisd(th, axis).toRotationMatrix());
      },
      [&](double tau) {
        return Eigen::Vector3d(dir * peak_g * std::sin(kPi * std::min(tau / kKnockS, 1.0)));
      },
      out);
}

void SimulatedRawTag::Reseat(double duration_s, std::vector<RawTagSample>* out) {
  impl_->TurnTo(impl_->Pose(UpBody()), duration_s, out);
}

}  // namespace metro
