#include "metro/station/protocol.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace metro::station {

namespace {
constexpr double kPi = 3.14159265358979323846;

std::string SignedAxes(const Eigen::Vector3d& v) {
  std::string s;
  for (int a = 0; a < 3; ++a) {
    if (v[a] == 0) continue;
    s += fmt::format("{}{}", v[a] > 0 ? '+' : '-', "XYZ"[a]);
  }
  return s;
}

std::vector<ProtocolPose> CubePoses(bool ferraris_order) {
  std::vector<ProtocolPose> out;
  // Ferraris: Z up, X up, Z down, X down (turns about Y), Y up, Y down (turns about X).
  const int faces[6][2] = {{2, 1}, {0, 1}, {2, -1}, {0, -1}, {1, 1}, {1, -1}};
  const int plain[6][2] = {{2, 1}, {2, -1}, {0, 1}, {0, -1}, {1, 1}, {1, -1}};
  for (const auto& f : ferraris_order ? faces : plain) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    v[f[0]] = f[1];
    out.push_back({v, fmt::format("{} {}", "XYZ"[f[0]], f[1] > 0 ? "up" : "down"), true});
  }
  for (int x : {1, -1}) {
    for (int y : {1, -1}) {
      for (int z : {1, -1}) {
        const Eigen::Vector3d v(x, y, z);
        out.push_back({v.normalized(), fmt::format("corner {} up", SignedAxes(v)), false});
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    for (int s1 : {1, -1}) {
      for (int s2 : {1, -1}) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        v[a] = s1;
        v[(a + 1) % 3] = s2;
        out.push_back({v.normalized(), fmt::format("edge {} up", SignedAxes(v)), false});
      }
    }
  }
  return out;
}

std::vector<ProtocolPose> SpherePoses(int n) {
  std::vector<ProtocolPose> out;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Eigen::Vector3d v(r * std::cos(golden * i), r * std::sin(golden * i), z);
    const double elevation = std::asin(std::clamp(z, -1.0, 1.0)) * 180.0 / kPi;
    const double azimuth = std::atan2(v.y(), v.x()) * 180.0 / kPi;
    out.push_back(
        {v, fmt::format("sphere {} (Z {:+.0f} deg, az {:+.0f} deg)", i + 1, elevation, azimuth),
         false});
  }
  return out;
}

}  // namespace

const char* ProtocolName(Protocol p) {
  switch (p) {
    case Protocol::kSixFace:
      return "six-face";
    case Protocol::kFerraris:
      return "ferraris";
    case Protocol::kSphere:
      return "sphere";
  }
  return "six-face";
}

std::optional<Protocol> ParseProtocol(std::string_view name) {
  for (Protocol p : {Protocol::kSixFace, Protocol::kFerraris, Protocol::kSphere}) {
    if (name == ProtocolName(p)) return p;
  }
  return std::nullopt;
}

std::vector<ProtocolPose> ProtocolPoses(Protocol p) {
  if (p == Protocol::kSphere) return SpherePoses(32);
  return CubePoses(p == Protocol::kFerraris);
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi;
}

int NearestWithin(const std::vector<Eigen::Vector3d>& taken, const Eigen::Vector3d& up_body,
                  double limit_deg) {
  int best = -1;
  double best_deg = limit_deg;
  for (size_t i = 0; i < taken.size(); ++i) {
    const double d = AngleDeg(taken[i], up_body);
    if (d <= best_deg) {
      best_deg = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

int ChooseNextPose(Protocol p, const std::vector<ProtocolPose>& poses,
                   const std::vector<Eigen::Vector3d>& taken, double min_separation_deg) {
  int best = -1;
  double best_min = -1;
  for (size_t i = 0; i < poses.size(); ++i) {
    if (NearestWithin(taken, poses[i].up_body, min_separation_deg) >= 0) continue;
    if (poses[i].face && p != Protocol::kSphere) return static_cast<int>(i);
    double min_deg = 180.0;
    for (const Eigen::Vector3d& t : taken)
      min_deg = std::min(min_deg, AngleDeg(t, poses[i].up_body));
    if (min_deg > best_min + 1e-9) {
      best_min = min_deg;
      best = static_cast<int>(i);
    }
  }
  return best;
}

std::string TurnInstruction(const Eigen::Vector3d& from_up, const Eigen::Vector3d& to_up) {
  // The body turns by R with R^T from_up = to_up in body coordinates: the world's up seen from
  // the body moves from from_up to to_up, so the body turns by the inverse of that rotation.
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(to_up, from_up);
  const Eigen::AngleAxisd aa(q);
  const double angle = aa.angle() * 180.0 / kPi;
  if (angle < 1.0) return "stay";
  Eigen::Vector3d axis = aa.axis();
  int a = 0;
  axis.cwiseAbs().maxCoeff(&a);
  const bool named = std::abs(axis[a]) > 0.98;
  if (named) {
    return fmt::format("turn {:.0f} deg about body {}{} (right-hand)", angle,
                       axis[a] > 0 ? '+' : '-', "XYZ"[a]);
  }
  return fmt::format("turn {:.0f} deg about body axis ({:+.2f}, {:+.2f}, {:+.2f})", angle, axis.x(),
                     axis.y(), axis.z());
}

}  // namespace metro::station
