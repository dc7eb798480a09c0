// metro's MCAP reader against the public MCAP conformance files (foxglove/mcap
// tests/conformance/data, datasets/external/mcap_conformance/SOURCE.md): each file's record
// walk must give what the JSON beside it (written by the MCAP project) lists: the Message
// records in file order with their channel's topic and message encoding, the schema name,
// log times and payload bytes; the chunk count; and whether the Footer points at a summary.
// The files hold no sensor_msgs/Imu, so this tests the record level only; the Imu decode is
// tested on @mcap/core's files in ros_log_test.cpp.
#include <catch2/catch.hpp>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "metro/io/ros_log.hpp"
#include "metro/io/session_io.hpp"

namespace metro {
namespace {

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/mcap_conformance/";

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A record's field as the conformance JSON writes it: [["name", value], ...].
const nlohmann::json& Field(const nlohmann::json& record, const std::string& name) {
  for (const nlohmann::json& f : record["fields"]) {
    if (f[0] == name) return f[1];
  }
  FAIL("no field " << name << " in " << record.dump());
  static const nlohmann::json none;
  return none;
}

// Bytes written as an array of decimal strings.
std::string Bytes(const nlohmann::json& a) {
  std::string out;
  for (const nlohmann::json& b : a)
    out.push_back(static_cast<char>(std::stoi(b.get<std::string>())));
  return out;
}

struct Message {
  std::string topic, encoding, type, data;
  int64_t log_time_ns = 0;
};

struct Expected {
  std::vector<Message> messages;
  int64_t chunks = 0;
  bool summary = false;
  size_t channels = 0;
};

Expected ExpectedOf(const nlohmann::json& j, bool chunked) {
  std::map<std::string, std::string> schema_name;  // id -> name
  std::map<std::string, Message> channel;          // id -> topic, encoding, schema name
  Expected out;
  for (const nlohmann::json& r : j["records"]) {
    const std::string type = r["type"];
    if (type == "Schema") schema_name[Field(r, "id")] = Field(r, "name");
    if (type == "Channel" && channel.count(Field(r, "id")) == 0) {
      Message c;
      c.topic = Field(r, "topic");
      c.encoding = Field(r, "message_encoding");
      const std::string schema = Field(r, "schema_id");
      c.type = schema == "0" ? "" : schema_name.at(schema);
      channel[Field(r, "id")] = c;
    }
    if (type == "Message") {
      Message m = channel.at(Field(r, "channel_id"));
      m.log_time_ns = std::stoll(Field(r, "log_time").get<std::string>());
      m.data = Bytes(Field(r, "data"));
      out.messages.push_back(m);
    }
    if (type == "Footer") out.summary = Field(r, "summary_start") != "0";
  }
  // The streamed listing shows a chunk's records, not the Chunk; the generator writes one
  // chunk holding every Schema, Channel and Message when the "ch" feature is on.
  out.chunks = chunked ? 1 : 0;
  out.channels = channel.size();
  return out;
}

TEST_CASE("MCAP conformance files: the record walk gives what their JSON lists",
          "[io][ros][mcap][conformance]") {
  const char* files[] = {
      "TenMessages/TenMessages",
      "TenMessages/TenMessages-st-sum",
      "TenMessages/TenMessages-ch",
      "TenMessages/TenMessages-ch-mx",
      "TenMessages/TenMessages-ch-chx-mx-rch-rsh",
      "TenMessages/TenMessages-ch-chx-mx-pad-rch-rsh-st-sum",
      "OneSchemalessMessage/OneSchemalessMessage",
      "OneSchemalessMessage/OneSchemalessMessage-ch-chx-mx-st-sum",
      "OneMetadata/OneMetadata-mdx-st-sum",
      "OneAttachment/OneAttachment-ax-st-sum",
      "NoData/NoData",
      "NoData/NoData-st-sum",
  };
  for (const std::string name : files) {
    INFO(name);
    const std::string path = kDir + name + ".mcap";
    const nlohmann::json j = nlohmann::json::parse(Slurp(kDir + name + ".json"));
    const bool chunked = name.find("-ch") != std::string::npos;
    const Expected want = ExpectedOf(j, chunked);
    std::vector<Message> got;
    auto log = ReadMcap(path, {}, [&](const RosLog& l, const RosMessageView& m) {
      const RosConnection& c = l.connections[m.connection];
      got.push_back(Message{c.topic, c.encoding, c.type, std::string(m.data), m.log_time_ns});
      CHECK(m.index == static_cast<int64_t>(got.size()));
      return Status::Ok();
    });
    REQUIRE(log.ok());
    CHECK(log.value().message_count == static_cast<int64_t>(want.messages.size()));
    CHECK(log.value().connections.size() == want.channels);
    CHECK(log.value().chunk_count == want.chunks);
    CHECK(log.value().has_summary == want.summary);
    REQUIRE(got.size() == want.messages.size());
    for (size_t i = 0; i < got.size(); ++i) {
      INFO("message " << i + 1);
      CHECK(got[i].topic == want.messages[i].topic);
      CHECK(got[i].encoding == want.messages[i].encoding);
      CHECK(got[i].type == want.messages[i].type);
      CHECK(got[i].log_time_ns == want.messages[i].log_time_ns);
      CHECK(got[i].data == want.messages[i].data);
    }
  }
  // TenMessages' log times are written out of order (0 2 1 3 3 5 4 7 8 9): the walk keeps
  // file order, as the JSON lists it; ordering is the session's stage (--time-order).
  const nlohmann::json ten =
      nlohmann::json::parse(Slurp(kDir + "TenMessages/TenMessages-ch-mx.json"));
  std::vector<int64_t> times;
  auto log = ReadMcap(kDir + "TenMessages/TenMessages-ch-mx.mcap", {},
                      [&](const RosLog&, const RosMessageView& m) {
                        times.push_back(m.log_time_ns);
                        return Status::Ok();
                      });
  REQUIRE(log.ok());
  CHECK(times == std::vector<int64_t>{0, 2, 1, 3, 3, 5, 4, 7, 8, 9});
  CHECK(ExpectedOf(ten, true).messages.size() == 10);
}

TEST_CASE("MCAP conformance files without sensor_msgs/Imu: the session error lists the topics",
          "[io][ros][mcap][conformance]") {
  auto r = LoadSession(kDir + "TenMessages/TenMessages-st-sum.mcap");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == kDir + "TenMessages/TenMessages-st-sum.mcap");
  CHECK(r.error().message ==
        "no sensor_msgs/Imu messages; expected an IMU topic (the log's topics: example "
        "(Example, 10 messages))");
}

}  // namespace
}  // namespace metro
