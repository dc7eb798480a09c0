// The calibration station's protocols (docs/station.md "Protocols"): the orientations the guide
// asks for, their names, and the choice of the next one.
//
// An orientation is named by the body direction that points up (the accelerometer's specific
// force at rest, +1 g along it): "Z up" is the tag flat on its back face, "X down" has the
// body x axis pointing to the floor.
//
//   six-face  the six faces first (every axis up and down, in any order), then the 8 corners
//             and 12 edges of the cube as the targets need them: six faces alone determine at
//             most 6 constants (the full accelerometer model has 9 and needs 10 distinct
//             orientations, docs/calibration-model.md "Uncertainty").
//   sphere    32 directions of a Fibonacci sphere, farthest from those taken first.
//   ferraris  the six faces in a fixed order, each reached by one named quarter or half turn
//             about a body axis (Ferraris et al., Sensors and Materials 7 (1995) 311: faces
//             and rotations about each axis), then the corners and edges as six-face.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace metro::station {

enum class Protocol { kSixFace, kFerraris, kSphere };
const char* ProtocolName(Protocol p);  // "six-face", "ferraris", "sphere"
std::optional<Protocol> ParseProtocol(std::string_view name);

struct ProtocolPose {
  Eigen::Vector3d up_body = Eigen::Vector3d::UnitZ();  // Unit body direction pointing up.
  std::string name;                                    // "Z up", "corner +X-Y+Z up", ...
  bool face = false;                                   // One of the six faces.
};

// The protocol's orientations in the order the guide offers them (faces first).
std::vector<ProtocolPose> ProtocolPoses(Protocol p);

// Angle between two unit directions [deg].
double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// The index of the taken direction nearest to `up_body` within `limit_deg`, or -1.
int NearestWithin(const std::vector<Eigen::Vector3d>& taken, const Eigen::Vector3d& up_body,
                  double limit_deg);

// The next orientation to ask for: among the protocol's poses farther than min_separation_deg
// from every taken direction, the first face not taken (ferraris: in its fixed order), else the
// one farthest from the taken directions (greatest minimum angle; ties: protocol order). -1
// when none is left (the protocol is complete).
int ChooseNextPose(Protocol p, const std::vector<ProtocolPose>& poses,
                   const std::vector<Eigen::Vector3d>& taken, double min_separation_deg);

// Ferraris: the turn from `from_up` to `to_up`, named for the operator: "turn 90 deg about
// body X (right-hand)", or "turn 180 deg about body Y". Any protocol may show it.
std::string TurnInstruction(const Eigen::Vector3d& from_up, const Eigen::Vector3d& to_up);

}  // namespace metro::station
