// PX4 ULog reader and loader against PX4's sample logs (datasets/external/px4_pyulog_samples):
// message counts and dropouts against pyulog's `ulog_info` output written beside them (an
// independent reader), sample values against a hand decode of the message bytes done here
// (a walk over the 3-byte message headers and memcpy of the floats, not the reader's code).
#include "metro/io/ulog.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

const std::string kDir = std::string(METRO_EXTERNAL_DATA_DIR) + "/px4_pyulog_samples/";

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// pyulog's ulog_info table: " name (multi id, message size in bytes)   count   total bytes".
struct InfoRow {
  std::string topic;
  int multi_id = 0;
  size_t size_bytes = 0;
  int64_t count = 0;
};
struct InfoFile {
  std::vector<InfoRow> rows;
  std::string dropouts;  // The "Dropouts: ..." or "No Dropouts" line.
};

InfoFile ParseInfo(const std::string& path) {
  InfoFile out;
  std::istringstream in(Slurp(path));
  std::string line;
  bool table = false;
  while (std::getline(in, line)) {
    if (line.rfind("Dropouts:", 0) == 0 || line.rfind("No Dropouts", 0) == 0) out.dropouts = line;
    if (line.rfind("Name (multi id", 0) == 0) {
      table = true;
      continue;
    }
    if (!table || line.empty()) continue;
    InfoRow r;
    char open = 0, comma = 0, close = 0;
    int64_t total = 0;
    std::istringstream fields(line);
    fields >> r.topic >> open >> r.multi_id >> comma >> r.size_bytes >> close >> r.count >> total;
    REQUIRE(open == '(');
    REQUIRE(close == ')');
    REQUIRE(total == r.count * static_cast<int64_t>(r.size_bytes));
    out.rows.push_back(r);
  }
  return out;
}

// The test's own walk over the messages: offset and type of each (no appended-data rules:
// the sample files' sections follow each other exactly).
struct RawMessage {
  size_t offset;
  char type;
  uint16_t size;
};
std::vector<RawMessage> Walk(const std::string& b) {
  std::vector<RawMessage> out;
  size_t p = 16;
  while (p + 3 <= b.size()) {
    const uint16_t size = static_cast<uint16_t>(static_cast<unsigned char>(b[p]) |
                                                (static_cast<unsigned char>(b[p + 1]) << 8));
    if (p + 3 + size > b.size()) break;
    out.push_back({p, b[p + 2], size});
    p += 3 + size;
  }
  return out;
}
uint16_t U16(const std::string& b, size_t at) {
  uint16_t v;
  std::memcpy(&v, b.data() + at, 2);
  return v;
}
// The msg_id the test's walk finds subscribed for topic[multi_id].
int MsgId(const std::string& b, const std::vector<RawMessage>& ms, const std::string& topic,
          int multi_id) {
  for (const RawMessage& m : ms) {
    if (m.type == 'A' && std::string(b.data() + m.offset + 6, m.size - 3) == topic &&
        static_cast<unsigned char>(b[m.offset + 3]) == multi_id) {
      return U16(b, m.offset + 4);
    }
  }
  return -1;
}
std::vector<size_t> DataOffsets(const std::string& b, const std::vector<RawMessage>& ms,
                                int msg_id) {
  std::vector<size_t> out;
  for (const RawMessage& m : ms) {
    if (m.type == 'D' && U16(b, m.offset + 3) == msg_id) out.push_back(m.offset + 5);
  }
  return out;
}
float F32(const std::string& b, size_t at) {
  float v;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}
uint64_t U64(const std::string& b, size_t at) {
  uint64_t v;
  std::memcpy(&v, b.data() + at, 8);
  return v;
}

void CheckAgainstInfo(const std::string& ulg, const std::string& info_txt) {
  const InfoFile info = ParseInfo(kDir + info_txt);
  REQUIRE(info.rows.size() >= 15);
  auto log = ReadULog(kDir + ulg);
  REQUIRE(log.ok());
  size_t with_data = 0;
  for (const ULogSubscription& s : log.value().subscriptions) with_data += s.message_count > 0;
  CHECK(with_data == info.rows.size());  // ulog_info lists the topics with data.
  for (const InfoRow& r : info.rows) {
    INFO(ulg << ": " << r.topic << "[" << r.multi_id << "]");
    const ULogSubscription* found = nullptr;
    for (const ULogSubscription* s : log.value().Find(r.topic)) {
      if (s->multi_id == r.multi_id) found = s;
    }
    REQUIRE(found != nullptr);
    CHECK(found->message_count == r.count);
    CHECK(log.value().FormatOf(*found).logged_size_bytes == r.size_bytes);
  }
}

TEST_CASE("ULog: every topic's message count and size equal pyulog's ulog_info", "[io][ulog]") {
  CheckAgainstInfo("sample.ulg", "sample_info.txt");
  CheckAgainstInfo("sample_appended_multiple.ulg", "sample_appended_multiple_info.txt");
}

TEST_CASE("ULog: dropouts as ulog_info counts them", "[io][ulog]") {
  // "Dropouts: count: 4, total duration: 0.1 s, max: 62 ms, mean: 29 ms"
  const InfoFile info = ParseInfo(kDir + "sample_info.txt");
  int count = 0, max_ms = 0, mean_ms = 0;
  double total_s = 0;
  REQUIRE(std::sscanf(info.dropouts.c_str(),
                      "Dropouts: count: %d, total duration: %lf s, max: %d ms, mean: %d ms", &count,
                      &total_s, &max_ms, &mean_ms) == 4);
  auto log = ReadULog(kDir + "sample.ulg");
  REQUIRE(log.ok());
  const ULog& l = log.value();
  CHECK(l.dropout_count == count);
  CHECK(l.dropout_max_ms == max_ms);
  // ulog_info prints the mean truncated to whole ms (119 / 4 = 29.75 -> 29).
  CHECK(l.dropout_total_ms / l.dropout_count == mean_ms);
  CHECK(std::round(l.dropout_total_ms / 100.0) / 10.0 == total_s);  // ulog_info's 0.1 s.
  CHECK(l.version == 0);  // A version 0 file: no 'B' message.
  // pyulog's ulog_messages output: one line per logged text message.
  const std::string messages = Slurp(kDir + "sample_messages.txt");
  CHECK(l.log_message_count == std::count(messages.begin(), messages.end(), '\n'));
  CHECK(l.log_message_count == 4);
  const InfoFile appended = ParseInfo(kDir + "sample_appended_multiple_info.txt");
  CHECK(appended.dropouts == "No Dropouts");
  auto a = ReadULog(kDir + "sample_appended_multiple.ulg");
  REQUIRE(a.ok());
  CHECK(a.value().dropout_count == 0);
  // Three appended sections (the flag bits' offsets); nothing cut between them.
  CHECK(a.value().appended_offsets.size() == 3);
  CHECK(a.value().cut_bytes == 0);
  CHECK(a.value().incompat_flags[0] == 1);
}

TEST_CASE("ULog: sensor_combined loads bit for bit as a session", "[io][ulog]") {
  const std::string path = kDir + "sample.ulg";
  CHECK(DetectSessionFormat(path).value() == SessionFormat::kULog);
  auto r = LoadSession(path);
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.format == SessionFormat::kULog);
  REQUIRE(s.tags.size() == 1);
  const Tag& t = s.tags[0];
  REQUIRE(t.size() == 17070);
  // The hand decode: 'F' sensor_combined is "uint64_t timestamp;float[3] gyro_rad;float
  // gyro_integral_dt;int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;..."
  // so timestamp at byte 0, gyro_rad at 8, accelerometer_m_s2 at 28 of the fields.
  const std::string b = Slurp(path);
  const auto ms = Walk(b);
  const int id = MsgId(b, ms, "sensor_combined", 0);
  REQUIRE(id >= 0);
  const auto offsets = DataOffsets(b, ms, id);
  REQUIRE(offsets.size() == 17070);
  const uint64_t t0 = U64(b, offsets[0]);
  for (size_t i : {size_t{0}, size_t{1}, size_t{8535}, size_t{17069}}) {
    INFO("sample " << i);
    const size_t at = offsets[i];
    CHECK(t.t_ns[i] == static_cast<int64_t>(U64(b, at)) * 1000);
    CHECK(t.t_s[i] == static_cast<double>(U64(b, at) - t0) * 1e-6);
    const char* gyro[3] = {"gx_rads", "gy_rads", "gz_rads"};
    const char* acc[3] = {"ax_mps2", "ay_mps2", "az_mps2"};
    for (int k = 0; k < 3; ++k) {
      CHECK(t.Find(gyro[k])->values[i] == static_cast<double>(F32(b, at + 8 + 4 * k)));
      CHECK(t.Find(acc[k])->values[i] == static_cast<double>(F32(b, at + 28 + 4 * k)));
    }
  }
  // accelerometer_timestamp_relative (int32 at byte 24): 0 in every message of this log, so
  // the note says the accelerometer columns carry the gyroscope's time with no offset.
  bool all_zero = true;
  for (size_t at : offsets) all_zero = all_zero && U64(b, at + 24) % (uint64_t{1} << 32) == 0;
  CHECK(all_zero);
  CHECK(std::count(s.input.notes.begin(), s.input.notes.end(),
                   "sensor_combined[0]: accelerometer_timestamp_relative 0 us; the accelerometer "
                   "columns carry the gyroscope's time") == 1);
  CHECK(t.Find("gx_rads")->unit == "rad/s");
  CHECK(t.Find("az_mps2")->unit == "m/s^2");
  CHECK(t.t_s[0] == 0.0);
  CHECK(s.input.time_unit == "us");
  CHECK(s.input.time_origin_ns == static_cast<int64_t>(t0) * 1000);
  // First sample's az: the value the hand decode printed, -9.63039493560791 m/s^2 (gravity).
  CHECK(t.Find("az_mps2")->values[0] == Approx(-9.63039493560791).epsilon(1e-7));
}

TEST_CASE("ULog: multi-instance sensor_accel, sensor_gyro and vehicle_imu", "[io][ulog]") {
  const std::string path = kDir + "sample_log_small.ulg";
  const std::string b = Slurp(path);
  const auto ms = Walk(b);
  // Default: sensor_combined, whose trailing padding (uint8_t[3] _padding0) is not logged.
  auto def = LoadSession(path);
  REQUIRE(def.ok());
  REQUIRE(def.value().tags.size() == 1);
  CHECK(def.value().tags[0].size() ==
        DataOffsets(b, ms, MsgId(b, ms, "sensor_combined", 0)).size());
  LoadOptions o;
  o.topics = {"sensor_accel", "sensor_gyro"};
  auto r = LoadSession(path, o);
  REQUIRE(r.ok());
  const Session& s = r.value();
  // Three instances of each; instance k of both sampled at the same instants (checked here
  // on the raw bytes), so each pair is one tag.
  REQUIRE(s.tags.size() == 3);
  int64_t messages = 0;
  for (int k = 0; k < 3; ++k) {
    const auto acc = DataOffsets(b, ms, MsgId(b, ms, "sensor_accel", k));
    const auto gyro = DataOffsets(b, ms, MsgId(b, ms, "sensor_gyro", k));
    messages += static_cast<int64_t>(acc.size() + gyro.size());
    INFO("instance " << k);
    const Tag& t = s.tags[k];
    CHECK(t.sensor == k + 1);
    REQUIRE(!acc.empty());
    REQUIRE(t.size() == acc.size());
    REQUIRE(t.size() == gyro.size());
    // Layout of both: uint64_t timestamp; uint64_t timestamp_sample; uint32_t device_id;
    // float x; float y; float z; float temperature; ...: time from timestamp_sample (byte 8).
    for (size_t i = 0; i < acc.size(); ++i) {
      REQUIRE(U64(b, acc[i] + 8) == U64(b, gyro[i] + 8));
      CHECK(t.t_ns[i] == static_cast<int64_t>(U64(b, acc[i] + 8)) * 1000);
      CHECK(t.Find("ax_mps2")->values[i] == F32(b, acc[i] + 20));
      CHECK(t.Find("az_mps2")->values[i] == F32(b, acc[i] + 28));
      CHECK(t.Find("gx_rads")->values[i] == F32(b, gyro[i] + 20));
      CHECK(t.Find("gz_rads")->values[i] == F32(b, gyro[i] + 28));
      CHECK(t.Find("temp_c")->values[i] == F32(b, acc[i] + 32));
    }
  }
  CHECK(s.rows == messages);
  {
    // One gyroscope sample 1 us later: that instance's two sensors stay two tags.
    std::string shifted = b;
    const size_t at = DataOffsets(b, ms, MsgId(b, ms, "sensor_gyro", 0))[2] + 8;
    shifted[at] = static_cast<char>(shifted[at] + 1);
    TempFile file(shifted, ".ulg");
    auto apart = LoadSession(file.path(), o);
    REQUIRE(apart.ok());
    CHECK(apart.value().tags.size() == 4);
    CHECK(apart.value().tags[0].Find("gx_rads") == nullptr);
    CHECK(apart.value().tags[3].Find("ax_mps2") == nullptr);
    CHECK(std::count(apart.value().input.notes.begin(), apart.value().input.notes.end(),
                     "sensor_accel[0] and sensor_gyro[0] have different sample times: two "
                     "tags") == 1);
  }
  // vehicle_imu: uint64_t timestamp; uint64_t timestamp_sample; uint32_t accel_device_id;
  // uint32_t gyro_device_id; float[3] delta_angle (24); float[3] delta_velocity (36);
  // uint16_t delta_angle_dt (48); uint16_t delta_velocity_dt (50). Rate = delta / dt.
  o.topics = {"vehicle_imu"};
  auto v = LoadSession(path, o);
  REQUIRE(v.ok());
  REQUIRE(v.value().tags.size() == 3);
  const auto offsets = DataOffsets(b, ms, MsgId(b, ms, "vehicle_imu", 0));
  const Tag& t = v.value().tags[0];
  REQUIRE(t.size() == offsets.size());
  const size_t at = offsets[0];
  CHECK(t.Find("gy_rads")->values[0] ==
        static_cast<double>(F32(b, at + 28)) / (U16(b, at + 48) * 1e-6));
  CHECK(t.Find("ax_mps2")->values[0] ==
        static_cast<double>(F32(b, at + 36)) / (U16(b, at + 50) * 1e-6));
  // One instance: NAME[K] or NAME:K.
  o.topics = {"sensor_gyro[2]", "sensor_accel:0"};
  auto one = LoadSession(path, o);
  REQUIRE(one.ok());
  REQUIRE(one.value().tags.size() == 2);
  CHECK(one.value().tags[0].size() == DataOffsets(b, ms, MsgId(b, ms, "sensor_gyro", 2)).size());
  CHECK(one.value().tags[0].Find("ax_mps2") == nullptr);  // Instances 2 and 0: not paired.
  CHECK(one.value().input.notes[0] ==
        "sensor 1 = sensor_gyro[2] (6 messages, time from timestamp_sample)");
  CHECK(one.value().input.notes[1] ==
        "sensor 2 = sensor_accel[0] (6 messages, time from timestamp_sample)");
  o.topics = {"sensor_gyro", "sensor_gyro[1]"};
  auto twice = LoadSession(path, o);
  REQUIRE_FALSE(twice.ok());
  CHECK_THAT(twice.error().message, Catch::Contains("--topic sensor_gyro[1]: that instance is "
                                                    "chosen twice"));
  o.topics = {"sensor_gyro[7]"};
  auto absent = LoadSession(path, o);
  REQUIRE_FALSE(absent.ok());
  CHECK_THAT(absent.error().message, Catch::Contains("--topic sensor_gyro[7]: the log has no"));
  // A topic the log lacks, a topic that is not an IMU's: errors that list the IMU topics.
  o.topics = {"vehicle_attitude"};
  auto bad = LoadSession(path, o);
  REQUIRE_FALSE(bad.ok());
  CHECK_THAT(bad.error().message, Catch::Contains("--topic vehicle_attitude: not an IMU topic"));
  CHECK_THAT(bad.error().message, Catch::Contains("sensor_gyro[2] (6 messages)"));
  o.topics = {"sensor_accel"};
  auto none = LoadSession(kDir + "sample.ulg", o);
  REQUIRE_FALSE(none.ok());
  CHECK_THAT(none.error().message, Catch::Contains("the log has no sensor_accel messages"));
}

// A ULog written here, message by message, with what the sample logs lack: nested formats, a
// trailing padding left out, 'C', 'S', 'R', 'I' and a message cut where appended data starts.
class ULogWriter {
 public:
  ULogWriter() {
    bytes_ = std::string("ULog\x01\x12\x35\x01", 8);
    Put(uint64_t{1000}, 8);
  }
  template <typename T>
  void Put(T v, int n) {
    for (int i = 0; i < n; ++i)
      bytes_ += static_cast<char>((static_cast<uint64_t>(v) >> (8 * i)) & 0xff);
  }
  static std::string Le(uint64_t v, int n) {
    std::string s;
    for (int i = 0; i < n; ++i) s += static_cast<char>((v >> (8 * i)) & 0xff);
    return s;
  }
  static std::string F32Bytes(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return Le(u, 4);
  }
  void Message(char type, const std::string& body) {
    Put(body.size(), 2);
    bytes_ += type;
    bytes_ += body;
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

TEST_CASE("ULog: nested formats, padding, tagged text, sync, remove and a cut before appended data",
          "[io][ulog]") {
  ULogWriter w;
  // 'B': incompat_flags[0] bit 0, appended_offsets[0] patched below.
  w.Message('B', std::string(8, '\0') + std::string("\x01", 1) + std::string(7, '\0') +
                     std::string(24, '\0'));
  w.Message('F', "vec3:float x;float y;float z;");
  w.Message('F', "imu_sample:uint64_t timestamp;vec3[2] v;uint16_t dt;uint8_t[2] _padding0;");
  w.Message('F', "sensor_gyro:uint64_t timestamp;float x;float y;float z;float temperature;");
  w.Message('I', std::string("\x0b", 1) + "char[3] foo" + "bar");
  w.Message('A', std::string("\x00", 1) + ULogWriter::Le(5, 2) + "imu_sample");
  w.Message('A', std::string("\x00", 1) + ULogWriter::Le(6, 2) + "sensor_gyro");
  // imu_sample: 8 + 2 * 12 + 2 = 34 bytes logged of its 36 (the padding left out).
  w.Message('D', ULogWriter::Le(5, 2) + ULogWriter::Le(2000, 8) + std::string(24, '\x01') +
                     ULogWriter::Le(4000, 2));
  const float gyro[5][3] = {{0.5f, -0.25f, 1e-3f},
                            {0.75f, 0.f, -2.f},
                            {1.f, 2.f, 3.f},
                            {-0.5f, 0.125f, 7.f},
                            {3.f, 2.f, 1.f}};
  auto gyro_message = [&](int i) {
    std::string body = ULogWriter::Le(6, 2) + ULogWriter::Le(10000 + 2500 * i, 8);
    for (float v : gyro[i]) body += ULogWriter::F32Bytes(v);
    return body + ULogWriter::F32Bytes(25.0f + i);
  };
  for (int i = 0; i < 3; ++i) w.Message('D', gyro_message(i));
  w.Message('S', std::string("\x2f\x73\x13\x20\x25\x0c\xbb\x12", 8));
  w.Message('O', ULogWriter::Le(25, 2));
  w.Message('C', std::string("\x06", 1) + ULogWriter::Le(7, 2) + ULogWriter::Le(3000, 8) + "hi");
  w.Message('L', std::string("\x06", 1) + ULogWriter::Le(3100, 8) + "hello");
  w.Message('R', ULogWriter::Le(5, 2));
  // The logger stopped mid-message: 10 bytes of a 29-byte 'D' message, then appended data.
  const std::string cut = gyro_message(3);
  w.bytes() += ULogWriter::Le(cut.size(), 2) + "D" + cut.substr(0, 7);
  const uint64_t appended = w.bytes().size();
  for (int i = 3; i < 5; ++i) w.Message('D', gyro_message(i));
  w.bytes().replace(16 + 3 + 16, 8, ULogWriter::Le(appended, 8));
  TempFile file(w.bytes(), ".ulg");

  auto log = ReadULog(file.path());
  REQUIRE(log.ok());
  const ULog& l = log.value();
  REQUIRE(l.appended_offsets == std::vector<uint64_t>{appended});
  CHECK(l.cut_bytes == 10);
  CHECK(l.dropout_count == 1);
  CHECK(l.dropout_total_ms == 25);
  CHECK(l.sync_count == 1);
  CHECK(l.tagged_log_message_count == 1);
  CHECK(l.log_message_count == 1);
  CHECK(l.remove_count == 1);
  REQUIRE(l.info.size() == 1);
  CHECK(l.info[0].key == "foo");
  CHECK(l.info[0].value == "bar");
  const ULogSubscription& imu = *l.Find("imu_sample").at(0);
  CHECK(imu.message_count == 1);
  const ULogFormat& f = l.FormatOf(imu);
  CHECK(f.size_bytes == 36);
  CHECK(f.logged_size_bytes == 34);
  CHECK(f.Find("v")->element_size_bytes == 12);
  CHECK(f.Find("v")->size_bytes == 24);
  CHECK(f.Find("dt")->offset_bytes == 32);
  CHECK(l.Find("sensor_gyro").at(0)->message_count == 5);

  LoadOptions o;
  o.topics = {"sensor_gyro"};
  auto r = LoadSession(file.path(), o);
  REQUIRE(r.ok());
  const Tag& t = r.value().tags.at(0);
  REQUIRE(t.size() == 5);
  for (int i = 0; i < 5; ++i) {
    CHECK(t.t_s[i] == 2500e-6 * i);
    CHECK(t.Find("gx_rads")->values[i] == gyro[i][0]);
    CHECK(t.Find("gz_rads")->values[i] == gyro[i][2]);
    CHECK(t.Find("temp_c")->values[i] == 25.0 + i);
  }
  CHECK(r.value().input.time_source == "timestamp");  // No timestamp_sample in this format.
}

TEST_CASE("ULog: damaged copies give a session or an error at a byte offset, never a crash",
          "[io][ulog]") {
  const std::string good = Slurp(kDir + "sample_log_small.ulg");
  uint64_t state = 0x9e3779b97f4a7c15u;  // xorshift64: the same damage on every run.
  auto next = [&state] {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
  };
  int ok = 0, errors = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::string b = good;
    // Damage the definitions more often than the data: that is where a byte changes most.
    const size_t span = trial % 2 == 0 ? 60000 : b.size();
    for (int k = 0; k < 4; ++k) b[next() % span] = static_cast<char>(next() & 0xff);
    if (trial % 5 == 0) b.resize(next() % b.size());
    TempFile file(b, ".ulg");
    for (bool lenient : {false, true}) {
      LoadOptions o;
      o.format = SessionFormat::kULog;
      o.lenient = lenient;
      auto r = LoadSession(file.path(), o);
      if (r.ok()) {
        ++ok;
        bool consistent = true;
        for (const Tag& t : r.value().tags) {
          for (const Quantity& q : t.quantities) consistent &= q.values.size() == t.size();
          for (size_t i = 1; i < t.size(); ++i) consistent &= t.t_s[i] > t.t_s[i - 1];
        }
        CHECK(consistent);
      } else {
        ++errors;
        INFO(r.error().ToString());
        CHECK(r.error().file == file.path());
        const std::string& m = r.error().message;
        CHECK((m.rfind("byte offset ", 0) == 0 || m.find("--topic") != std::string::npos ||
               m.find("no sensor_combined") != std::string::npos || m.find("format '") == 0));
      }
    }
  }
  CHECK(ok > 0);
  CHECK(errors > 0);
}

// The offset of the message that runs past byte `n`.
size_t CutMessage(const std::vector<RawMessage>& ms, size_t n) {
  for (const RawMessage& m : ms) {
    if (m.offset + 3 + m.size > n) return m.offset;
  }
  return 0;
}

TEST_CASE("ULog: a truncated file is an error, or its complete messages with --lenient",
          "[io][ulog]") {
  const std::string b = Slurp(kDir + "sample_log_small.ulg");
  const auto ms = Walk(b);
  const size_t n = b.size() / 2 + 7;  // Somewhere inside a message.
  const size_t cut = CutMessage(ms, n);
  REQUIRE(cut > 0);
  REQUIRE(cut < n);
  TempFile file(b.substr(0, n), ".ulg");
  auto strict = LoadSession(file.path());
  REQUIRE_FALSE(strict.ok());
  CHECK(strict.error().file == file.path());
  CHECK_THAT(strict.error().message,
             Catch::StartsWith("byte offset " + std::to_string(cut) + ": truncated file: "));
  CHECK_THAT(strict.error().message,
             Catch::Contains("bytes, " + std::to_string(n - cut - 3) + " left after its header"));
  LoadOptions lenient;
  lenient.lenient = true;
  auto r = LoadSession(file.path(), lenient);
  REQUIRE(r.ok());
  CHECK(r.value().rejected_rows == 1);
  REQUIRE(r.value().rejected_lines.size() == 1);
  std::vector<RawMessage> complete;
  for (const RawMessage& m : ms) {
    if (m.offset < cut) complete.push_back(m);
  }
  CHECK(r.value().tags[0].size() ==
        DataOffsets(b, complete, MsgId(b, ms, "sensor_combined", 0)).size());
  auto log = ReadULog(file.path(), {true, {}});
  REQUIRE(log.ok());
  CHECK(log.value().truncated_bytes == static_cast<int64_t>(n - cut));
  CHECK(log.value().message_count == static_cast<int64_t>(complete.size()));
  // The lost message's index: the one after the complete ones.
  CHECK(r.value().rejected_lines[0] == static_cast<int64_t>(complete.size()) + 1);
}

TEST_CASE("ULog: out-of-order and repeated timestamps are sorted or refused (--time-order)",
          "[io][ulog]") {
  // sample.ulg's sensor_combined with two messages' payloads swapped (100 <-> 101: one
  // message late) and message 200's payload copied over 201's (a repeated timestamp), by
  // byte edits here; the payloads are equal-sized, so every other byte stays in place.
  const std::string path = kDir + "sample.ulg";
  const std::string good = Slurp(path);
  const auto ms = Walk(good);
  const auto offsets = DataOffsets(good, ms, MsgId(good, ms, "sensor_combined", 0));
  REQUIRE(offsets.size() == 17070);
  const size_t payload = 72;  // sensor_combined's size in sample_info.txt (ulog_info).
  std::string b = good;
  b.replace(offsets[100], payload, good.substr(offsets[101], payload));
  b.replace(offsets[101], payload, good.substr(offsets[100], payload));
  b.replace(offsets[201], payload, good.substr(offsets[200], payload));
  REQUIRE(U64(b, offsets[100]) > U64(b, offsets[101]));
  REQUIRE(U64(b, offsets[200]) == U64(b, offsets[201]));
  TempFile file(b, ".ulg");

  auto orig = LoadSession(path);
  REQUIRE(orig.ok());
  const Tag& o = orig.value().tags[0];
  auto sorted = LoadSession(file.path());
  REQUIRE(sorted.ok());
  const Tag& t = sorted.value().tags[0];
  REQUIRE(t.size() == 17069);  // 201 dropped: the first of the repeated pair is kept.
  const std::vector<std::string>& notes = sorted.value().input.notes;
  CHECK(std::count(notes.begin(), notes.end(),
                   "sensor_combined[0]: 1 messages out of timestamp order, sorted; 1 repeated "
                   "timestamp dropped (the first in the file kept) (--time-order sort)") == 1);
  // Sample i of the sorted tag is the file's message at offsets[j], decoded by hand.
  auto check = [&](size_t i, size_t j) {
    INFO("sorted sample " << i << " = file message " << j);
    CHECK(t.t_ns[i] == static_cast<int64_t>(U64(b, offsets[j])) * 1000);
    CHECK(t.Find("gx_rads")->values[i] == static_cast<double>(F32(b, offsets[j] + 8)));
    CHECK(t.Find("az_mps2")->values[i] == static_cast<double>(F32(b, offsets[j] + 36)));
    CHECK(t.line[i] == o.line[j]);  // The message index in the file, unchanged.
  };
  check(99, 99);
  check(100, 101);  // The earlier time, written second.
  check(101, 100);
  check(200, 200);
  check(201, 202);  // 201 (the repeat) dropped.
  check(17068, 17069);
  // And the sorted values are the untouched file's, apart from the dropped message.
  for (size_t i = 0; i < 17069; ++i) {
    const size_t j = i < 201 ? i : i + 1;
    if (t.t_ns[i] != o.t_ns[j] || t.Find("ax_mps2")->values[i] != o.Find("ax_mps2")->values[j]) {
      FAIL("sample " << i);
    }
  }

  LoadOptions refuse;
  refuse.time_order = LoadOptions::TimeOrder::kRefuse;
  auto r = LoadSession(file.path(), refuse);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() ==
        fmt::format("{}: byte offset {}: sensor_combined[0] message 102: timestamp {} us is not "
                    "after the previous message's {} us; expected increasing times "
                    "(--time-order sort sorts them)",
                    file.path(), offsets[101] - 5, U64(good, offsets[100]),
                    U64(good, offsets[101])));
  // Refused also when only the repeat is left (the swap undone).
  std::string repeat_only = b;
  for (size_t j : {size_t{100}, size_t{101}}) {
    repeat_only.replace(offsets[j], payload, good.substr(offsets[j], payload));
  }
  TempFile repeat_file(repeat_only, ".ulg");
  auto rr = LoadSession(repeat_file.path(), refuse);
  REQUIRE_FALSE(rr.ok());
  CHECK_THAT(rr.error().message,
             Catch::StartsWith(fmt::format("byte offset {}: sensor_combined[0] message 202: "
                                           "timestamp {} us is not after the previous "
                                           "message's {} us",
                                           offsets[201] - 5, U64(good, offsets[200]),
                                           U64(good, offsets[200]))));
}

TEST_CASE("ULog: bad input names the file and the byte offset", "[io][ulog]") {
  const std::string good = Slurp(kDir + "sample_log_small.ulg");
  const auto ms = Walk(good);
  LoadOptions ulog;
  ulog.format = SessionFormat::kULog;
  SECTION("bad magic") {
    std::string b = good;
    b[3] = 'X';
    TempFile file(b, ".ulg");
    CHECK(DetectSessionFormat(file.path()).ok() == false);  // Binary, not ULog: refused.
    auto r = LoadSession(file.path(), ulog);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().ToString() == file.path() +
                                      ": byte offset 0: expected the ULog magic 55 4c 6f 67 01 "
                                      "12 35 (\"ULog\" 01 12 35), found 55 4c 6f 58 01 12 35");
  }
  SECTION("unknown field type") {
    std::string b = good;
    const size_t f = b.find("vehicle_imu:uint64_t timestamp;");
    REQUIRE(f != std::string::npos);
    b.replace(b.find("float[3] delta_angle", f), 5, "flaot");
    size_t a_offset = 0;
    for (const RawMessage& m : ms) {
      if (m.type == 'A' && std::string(b.data() + m.offset + 6, m.size - 3) == "vehicle_imu") {
        a_offset = m.offset;
        break;
      }
    }
    TempFile file(b, ".ulg");
    auto r = ReadULog(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().ToString(),
               Catch::StartsWith(file.path() + ": byte offset " + std::to_string(a_offset) +
                                 ": format 'vehicle_imu', field 'flaot delta_angle': unknown "
                                 "type 'flaot'; expected int8_t"));
  }
  SECTION("a data message of an id never added") {
    std::string b = good;
    const auto offsets = DataOffsets(b, ms, MsgId(b, ms, "sensor_combined", 0));
    const size_t d = offsets[10] - 5;    // The message's header.
    b[d + 3] = static_cast<char>(0xe7);  // msg_id 999 (0x03e7): never subscribed.
    b[d + 4] = 0x03;
    TempFile file(b, ".ulg");
    auto r = LoadSession(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().ToString() == file.path() + ": byte offset " + std::to_string(d) +
                                      ": 'D' message of msg_id 999, which no 'A' message added "
                                      "(or an 'R' message removed): expected the msg_id of a "
                                      "subscribed topic");
    LoadOptions lenient;
    lenient.lenient = true;
    auto skipped = LoadSession(file.path(), lenient);
    REQUIRE(skipped.ok());
    CHECK(skipped.value().tags[0].size() == offsets.size() - 1);
    CHECK(skipped.value().rejected_rows == 1);
  }
  SECTION("an incompatible flag this reader does not know") {
    std::string b = good;
    REQUIRE(b[18] == 'B');
    b[16 + 3 + 8 + 1] = 0x04;  // incompat_flags[1]
    TempFile file(b, ".ulg");
    auto r = ReadULog(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().message,
               Catch::StartsWith("byte offset 28: incompat_flags[1] = 0x04: an incompatible flag"));
  }
  SECTION("a format larger than a message can hold") {
    ULogWriter w;
    w.Message('F', "part:float[20000] x;");  // 80,000 bytes: no uint16 msg_size holds it.
    w.Message('F', "big:uint64_t timestamp;part p;");
    const size_t a_offset = w.bytes().size();
    w.Message('A', std::string("\x00", 1) + ULogWriter::Le(1, 2) + "big");
    TempFile file(w.bytes(), ".ulg");
    auto r = ReadULog(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message == "byte offset " + std::to_string(a_offset) +
                                   ": format 'part' is more than 65535 bytes at field 'x': more "
                                   "than a message can hold (msg_size is a uint16)");
  }
  SECTION("a file shorter than the header") {
    TempFile file(good.substr(0, 10), ".ulg");
    auto r = LoadSession(file.path());
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().message, Catch::Contains("a 10-byte file: expected the 16-byte ULog"));
  }
  SECTION("--topic on a CSV session") {
    TempFile file("t_s,gx_dps\n0,1\n0.1,2\n");
    LoadOptions o;
    o.topics = {"sensor_combined"};
    auto r = LoadSession(file.path(), o);
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error().message,
               Catch::Contains("topics are chosen in ULog, MCAP, ROS bag and DataFlash input"));
  }
}

}  // namespace
}  // namespace metro
