// Private: sensor_msgs/Imu payloads decoded (ROS 1 serialization and ROS 2 CDR), for the
// ROS log loader (ros_session.cpp).
//
// sensor_msgs/Imu (both ROS versions, the same fields in the same order):
//   std_msgs/Header header   (ROS 1: uint32 seq, time stamp (uint32 sec, uint32 nsec),
//                             string frame_id; ROS 2: builtin_interfaces/Time stamp
//                             (int32 sec, uint32 nanosec), string frame_id)
//   geometry_msgs/Quaternion orientation            (float64 x, y, z, w)
//   float64[9] orientation_covariance                (row major; [0] = -1: no orientation)
//   geometry_msgs/Vector3 angular_velocity           (float64 x, y, z) [rad/s]
//   float64[9] angular_velocity_covariance
//   geometry_msgs/Vector3 linear_acceleration        (float64 x, y, z) [m/s^2]
//   float64[9] linear_acceleration_covariance
// ROS 1 serialization (wiki.ros.org/msg, "Serialization"): little endian, packed, strings
// as uint32 length + bytes. ROS 2 CDR (OMG DDS-XTypes 1.3, 7.4.1 "CDR" (version 1)): a
// 4-byte encapsulation header (00 01 = CDR little endian, 00 00 = big endian, then 2 option
// bytes), then each primitive aligned to its size counted from the end of that header;
// strings as uint32 length (with the NUL) + bytes + NUL.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace metro::internal {

struct ImuMessage {
  int64_t stamp_ns = 0;  // header.stamp: sec * 1e9 + nanosec.
  double orientation_xyzw[4] = {};
  double orientation_covariance[9] = {};
  double angular_velocity_rads[3] = {};
  double angular_velocity_covariance[9] = {};
  double linear_acceleration_mps2[3] = {};
  double linear_acceleration_covariance[9] = {};
};

// The message type names metro decodes as sensor_msgs/Imu.
bool IsImuType(std::string_view type);
// MD5 of ROS 1's sensor_msgs/Imu definition (what rosbag records in each connection).
constexpr std::string_view kRos1ImuMd5 = "6a62c6daae103f4ff57a132d6f95cec2";

// Decode one message; "" or what is wrong (with the byte offset in the payload).
std::string DecodeImuCdr(std::string_view data, ImuMessage* m);
std::string DecodeImuRos1(std::string_view data, ImuMessage* m);

}  // namespace metro::internal
