// MCAP, ROS 1 and ROS 2 bag readers and their sensor_msgs/Imu sessions against files written
// by independent writers (datasets/external/ros_samples/SOURCE.md: @mcap/core and
// @foxglove/rosmsg2-serialization, Debian's python3-rosbag, Python's sqlite3): every value
// read must equal, bit for bit, what the writer wrote (its JSON beside each file); then each
// class of bad input, made from those files.
#include "metro/io/ros_log.hpp"

#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/ros_samples/";

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json Expected(const std::string& name) {
  return nlohmann::json::parse(Slurp(kDir + name + ".expected.json"));
}

// Same bits (a NaN or -0.0 would differ from a value read through another path).
bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The loaded tag against the writer's messages of `topic`, in order.
void CheckTag(const Tag& tag, const nlohmann::json& messages, bool receive_time = false) {
  REQUIRE(tag.size() == messages.size());
  const char* gyro[3] = {"gx_rads", "gy_rads", "gz_rads"};
  const char* accel[3] = {"ax_mps2", "ay_mps2", "az_mps2"};
  const bool orientation = messages[0]["orientation_covariance"][0].get<double>() != -1.0;
  REQUIRE((tag.Find("qw") != nullptr) == orientation);
  int64_t mismatches = 0;
  for (size_t i = 0; i < messages.size(); ++i) {
    const nlohmann::json& m = messages[i];
    const std::string t = m[receive_time ? "log_time_ns" : "stamp_ns"].get<std::string>();
    if (tag.t_ns[i] != std::stoll(t)) ++mismatches;
    for (int k = 0; k < 3; ++k) {
      if (!SameBits(tag.Find(gyro[k])->values[i], m["angular_velocity"][k].get<double>()) ||
          !SameBits(tag.Find(accel[k])->values[i], m["linear_acceleration"][k].get<double>())) {
        ++mismatches;
      }
    }
    if (orientation) {
      const auto& q = m["orientation_xyzw"];
      if (!SameBits(tag.Find("qw")->values[i], q[3].get<double>()) ||
          !SameBits(tag.Find("qx")->values[i], q[0].get<double>()) ||
          !SameBits(tag.Find("qy")->values[i], q[1].get<double>()) ||
          !SameBits(tag.Find("qz")->values[i], q[2].get<double>())) {
        ++mismatches;
      }
    }
  }
  CHECK(mismatches == 0);
}

Session Load(const std::string& path, LoadOptions options = {}) {
  auto s = LoadSession(path, options);
  INFO((s.ok() ? std::string() : s.error().ToString()));
  REQUIRE(s.ok());
  return std::move(s).value();
}

std::string LoadError(const std::string& path, LoadOptions options = {}) {
  auto s = LoadSession(path, options);
  REQUIRE_FALSE(s.ok());
  return s.error().ToString();
}

bool HasNote(const Session& s, const std::string& part) {
  for (const std::string& n : s.input.notes) {
    if (n.find(part) != std::string::npos) return true;
  }
  return false;
}

TEST_CASE("MCAP files of @mcap/core read as written, every chunk kind", "[io][ros][mcap]") {
  struct Case {
    const char* name;
    SessionFormat format;
  };
  for (const Case& c :
       {Case{"imu_zstd", SessionFormat::kMcap}, Case{"imu_lz4", SessionFormat::kMcap},
        Case{"imu_none_nosummary", SessionFormat::kMcap},
        Case{"imu_unchunked", SessionFormat::kMcap}}) {
    SECTION(c.name) {
      const Session s = Load(kDir + c.name + ".mcap");
      CHECK(s.format == c.format);
      REQUIRE(s.tags.size() == 1);
      CheckTag(s.tags[0], Expected(c.name)["topics"]["/imu/data"]["messages"]);
      CHECK(HasNote(s, "sensor 1 = /imu/data (60 messages"));
      CHECK(HasNote(s,
                    "angular_velocity_covariance [(rad/s)^2] (row major, x y z) = [2.5e-07, 0, "
                    "0, 0, 2.5e-07, 0, 0, 0, 2.5e-07] in every message"));
    }
  }
}

TEST_CASE("MCAP: --time receive takes the log time", "[io][ros][mcap]") {
  LoadOptions o;
  o.ros_time = LoadOptions::RosTime::kReceive;
  const Session s = Load(kDir + "imu_lz4.mcap", o);
  CheckTag(s.tags[0], Expected("imu_lz4")["topics"]["/imu/data"]["messages"], true);
}

TEST_CASE("MCAP topics: counts and rates as written", "[io][ros][mcap]") {
  auto log = ReadMcap(kDir + "imu_none_nosummary.mcap", {}, nullptr);
  REQUIRE(log.ok());
  CHECK_FALSE(log.value().has_summary);
  REQUIRE(log.value().Find("/imu/data").size() == 1);
  CHECK(log.value().Find("/imu/data")[0]->message_count == 60);
  CHECK(log.value().Find("/imu/temperature")[0]->message_count == 5);
  CHECK(log.value().Find("/imu/data")[0]->type == "sensor_msgs/msg/Imu");
  // 60 messages 5 ms apart: 59 intervals over 0.295 s = 200 Hz.
  CHECK(FormatRosTopics(log.value())
            .find("/imu/data                        sensor_msgs/msg/Imu    "
                  "                    60     200.00") != std::string::npos);
  auto indexed = ReadMcap(kDir + "imu_zstd.mcap", {}, nullptr);
  REQUIRE(indexed.ok());
  CHECK(indexed.value().has_summary);
  CHECK(indexed.value().chunk_count >= 2);
}

TEST_CASE("Two IMU topics: listed when none is chosen, one tag each, stamps sorted",
          "[io][ros][mcap]") {
  const std::string path = kDir + "two_imus_zstd.mcap";
  CHECK(LoadError(path) ==
        path +
            ": 2 IMU topics: /imu0 (sensor_msgs/msg/Imu, 48 messages), /imu1 "
            "(sensor_msgs/msg/Imu, 24 messages); choose with --topic NAME (repeatable: each "
            "topic one tag)");
  LoadOptions o;
  o.topics = {"/imu1", "/imu0"};
  const Session s = Load(path, o);
  REQUIRE(s.tags.size() == 2);
  CHECK(s.tags[0].source_name == "/imu1");  // Each tag named by its topic, as chosen.
  CHECK(s.tags[1].source_name == "/imu0");
  const nlohmann::json e = Expected("two_imus_zstd")["topics"];
  CheckTag(s.tags[0], e["/imu1"]["messages"]);
  // /imu0 was written with stamps 10<->11 and 30<->31 swapped and 41 a repeat of 40: sorted,
  // the repeat dropped, the writer's messages in stamp order without it.
  nlohmann::json sorted = e["/imu0"]["messages"];
  std::swap(sorted[10], sorted[11]);
  std::swap(sorted[30], sorted[31]);
  sorted.erase(41);
  CheckTag(s.tags[1], sorted);
  CHECK(HasNote(s,
                "/imu0: 2 messages out of header.stamp order, sorted; 1 repeated header.stamp "
                "dropped"));
  o.time_order = LoadOptions::TimeOrder::kRefuse;
  CHECK(LoadError(path, o).find("message 19 (/imu0): header.stamp 1700000000173456789 ns is not "
                                "after the previous message's 1700000000178456789 ns; expected "
                                "increasing times") != std::string::npos);
}

TEST_CASE("ROS 1 bags of rosbag read as written: none, bz2, lz4, without index",
          "[io][ros][rosbag1]") {
  for (const char* name : {"ros1_none", "ros1_bz2", "ros1_lz4", "ros1_noindex"}) {
    SECTION(name) {
      const Session s = Load(kDir + name + ".bag");
      CHECK(s.format == SessionFormat::kRosbag1);
      REQUIRE(s.tags.size() == 1);
      // The bag without its index is the lz4 bag cut at index_pos (write_ros1_bags.py).
      const std::string json = std::string(name) == "ros1_noindex" ? "ros1_lz4" : name;
      CheckTag(s.tags[0], Expected(json)["topics"]["/imu/data"]["messages"]);
    }
  }
  auto log = ReadRosbag1(kDir + "ros1_noindex.bag", {}, nullptr);
  REQUIRE(log.ok());
  CHECK_FALSE(log.value().has_summary);
  CHECK(log.value().Find("/imu/temperature")[0]->message_count == 5);
}

TEST_CASE("ROS 2 bags: sqlite3 and MCAP storage read as written", "[io][ros][rosbag2]") {
  const Session sql = Load(kDir + "rosbag2_sqlite");
  CHECK(sql.format == SessionFormat::kRosbag2);
  CheckTag(sql.tags[0], Expected("rosbag2_sqlite")["topics"]["/imu/data"]["messages"]);
  const Session mcap = Load(kDir + "rosbag2_mcap/metadata.yaml");
  CHECK(mcap.format == SessionFormat::kRosbag2);
  CheckTag(mcap.tags[0], Expected("rosbag2_mcap")["topics"]["/imu/data"]["messages"]);
  CHECK(mcap.sha256.find('+') != std::string::npos);  // metadata.yaml + the storage file.
}

TEST_CASE("Truncated MCAP and ROS 1 bag: an error, or their complete records with --lenient",
          "[io][ros]") {
  const std::string mcap = Slurp(kDir + "imu_zstd.mcap");
  TempFile cut_mcap(mcap.substr(0, 6000), ".mcap");
  const std::string e = LoadError(cut_mcap.path());
  CHECK(e.find(": byte offset ") != std::string::npos);
  CHECK(e.find("runs past the file's end") != std::string::npos);
  LoadOptions lenient;
  lenient.lenient = true;
  const Session s = Load(cut_mcap.path(), lenient);
  CHECK(s.tags[0].size() > 0);
  CHECK(s.tags[0].size() < 60);
  CHECK(s.rejected_rows == 1);  // The cut record, counted.
  bool warned = false;
  for (const std::string& w : s.input.warnings) {
    warned = warned || w.find("truncated file: the last") != std::string::npos;
  }
  CHECK(warned);
  // Every message read is the writer's, in order.
  nlohmann::json first = Expected("imu_zstd")["topics"]["/imu/data"]["messages"];
  first.erase(first.begin() + static_cast<long>(s.tags[0].size()), first.end());
  CheckTag(s.tags[0], first);

  const std::string bag = Slurp(kDir + "ros1_none.bag");
  TempFile cut_bag(bag.substr(0, bag.size() / 2), ".bag");
  CHECK(LoadError(cut_bag.path()).find("a bag cut short: --lenient") != std::string::npos);
  const Session b = Load(cut_bag.path(), lenient);
  nlohmann::json bag_first = Expected("ros1_none")["topics"]["/imu/data"]["messages"];
  bag_first.erase(bag_first.begin() + static_cast<long>(b.tags[0].size()), bag_first.end());
  CheckTag(b.tags[0], bag_first);
}

// Offset of the first chunk record of an MCAP (opcode 0x06 after the magic and header).
size_t FirstChunk(const std::string& bytes) {
  size_t at = 8;
  while (at + 9 <= bytes.size() && bytes[at] != 0x06) {
    uint64_t len = 0;
    for (int i = 7; i >= 0; --i) len = (len << 8) | static_cast<unsigned char>(bytes[at + 1 + i]);
    at += 9 + len;
  }
  return at;
}

TEST_CASE("MCAP cut between records (no Data End, no footer): an error, or all with --lenient",
          "[io][ros][mcap]") {
  const std::string bytes = Slurp(kDir + "imu_none_nosummary.mcap");
  size_t at = 8;  // Walk the records to the Data End (opcode 0x0f).
  while (at + 9 <= bytes.size() && bytes[at] != 0x0f) {
    uint64_t len = 0;
    for (int i = 7; i >= 0; --i) len = (len << 8) | static_cast<unsigned char>(bytes[at + 1 + i]);
    at += 9 + len;
  }
  REQUIRE(at < bytes.size());
  TempFile cut(bytes.substr(0, at), ".mcap");
  CHECK(LoadError(cut.path()) ==
        cut.path() + ": byte offset " + std::to_string(at) +
            ": the file ends after 65 messages in complete records without MCAP's "
            "Footer record and closing magic; expected a complete file (a recording cut short: "
            "--lenient reads its complete records)");
  LoadOptions lenient;
  lenient.lenient = true;
  const Session s = Load(cut.path(), lenient);
  CheckTag(s.tags[0], Expected("imu_none_nosummary")["topics"]["/imu/data"]["messages"]);
}

TEST_CASE("MCAP bad chunk CRC and unknown compression: file, byte offset, what was expected",
          "[io][ros][mcap]") {
  std::string bytes = Slurp(kDir + "imu_none_nosummary.mcap");
  const size_t chunk = FirstChunk(bytes);
  REQUIRE(chunk < bytes.size());
  // Chunk body: start, end, uncompressed size (uint64), crc (uint32), compression, records.
  std::string bad_crc = bytes;
  bad_crc[chunk + 9 + 24] ^= 0x01;
  TempFile crc_file(bad_crc, ".mcap");
  const std::string e = LoadError(crc_file.path());
  CHECK(e.find(crc_file.path() + ": byte offset " + std::to_string(chunk) +
               ": Chunk: the chunk's "
               "records have CRC-32 ") != std::string::npos);
  CHECK(e.find("(a corrupt chunk)") != std::string::npos);

  std::string zstd = Slurp(kDir + "imu_zstd.mcap");
  const size_t z = FirstChunk(zstd);
  REQUIRE(zstd.substr(z + 9 + 32, 4) == "zstd");
  zstd.replace(z + 9 + 32, 4, "brot");
  TempFile codec_file(zstd, ".mcap");
  CHECK(LoadError(codec_file.path()) ==
        codec_file.path() + ": byte offset " + std::to_string(z) +
            ": Chunk: compression \"brot\": expected \"\" (none), \"zstd\" or \"lz4\"");
}

TEST_CASE("ROS 1 bag: unknown compression and a foreign sensor_msgs/Imu definition",
          "[io][ros][rosbag1]") {
  std::string bytes = Slurp(kDir + "ros1_bz2.bag");
  const size_t at = bytes.find("compression=bz2");
  REQUIRE(at != std::string::npos);
  bytes.replace(at + 12, 3, "xz2");
  TempFile codec(bytes, ".bag");
  CHECK(LoadError(codec.path())
            .find("chunk: compression \"xz2\": expected \"none\", \"bz2\" or "
                  "\"lz4\"") != std::string::npos);

  std::string md5 = Slurp(kDir + "ros1_none.bag");
  size_t m = 0;
  while ((m = md5.find("6a62c6daae103f4ff57a132d6f95cec2", m)) != std::string::npos) {
    md5[m] = '7';
  }
  TempFile other(md5, ".bag");
  CHECK(LoadError(other.path())
            .find("the connection's md5sum 7a62c6daae103f4ff57a132d6f95cec2 "
                  "is not sensor_msgs/Imu's 6a62c6daae103f4ff57a132d6f95cec2") !=
        std::string::npos);
}

TEST_CASE("A missing topic and a topic that is not sensor_msgs/Imu list the log's topics",
          "[io][ros]") {
  LoadOptions o;
  o.topics = {"/imu/raw"};
  const std::string path = kDir + "ros1_lz4.bag";
  CHECK(LoadError(path, o) ==
        path +
            ": --topic /imu/raw: no such topic; expected one of the log's: /imu/data "
            "(sensor_msgs/Imu, 60 messages), /imu/temperature (sensor_msgs/Temperature, 5 "
            "messages)");
  o.topics = {"/imu/temperature"};
  CHECK(LoadError(kDir + "rosbag2_sqlite", o) ==
        kDir +
            "rosbag2_sqlite: --topic /imu/temperature: its messages are "
            "sensor_msgs/msg/Temperature; expected sensor_msgs/Imu (the log's IMU topics: "
            "/imu/data (sensor_msgs/msg/Imu, 60 messages))");
}

}  // namespace
}  // namespace metro
