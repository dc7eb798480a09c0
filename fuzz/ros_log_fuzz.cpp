// libFuzzer target: MCAP files and ROS 1 bags (metro/io/ros_log.hpp), read from memory by
// both readers whatever the first bytes, then loaded as a session (the sensor_msgs/Imu
// decoding, topic choice and time ordering) strictly and with --lenient.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_input.hpp"
#include "metro/io/ros_log.hpp"
#include "metro/io/session_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  for (bool lenient : {false, true}) {
    metro::RosLogReadOptions read;
    read.lenient = lenient;
    auto mcap = metro::ReadMcapBytes("in.mcap", bytes, read, nullptr);
    if (mcap.ok()) (void)metro::FormatRosTopics(mcap.value());
    auto bag = metro::ReadRosbag1Bytes("in.bag", bytes, read, nullptr);
    if (bag.ok()) (void)metro::FormatRosTopics(bag.value());
  }
  const std::string& path = metro_fuzz::WriteInput(data, size, "log.bin");
  for (metro::SessionFormat f : {metro::SessionFormat::kMcap, metro::SessionFormat::kRosbag1}) {
    metro::LoadOptions options;
    options.format = f;
    (void)metro::LoadSession(path, options);
    options.lenient = true;
    options.time_order = metro::LoadOptions::TimeOrder::kRefuse;
    (void)metro::LoadSession(path, options);
  }
  return 0;
}
