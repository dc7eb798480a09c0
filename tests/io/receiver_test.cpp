#include "metro/io/receiver.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::TempFile;

std::string Line(int sensor, NewDataFlag flag, const Quaternion& q, uint8_t extra = 0xAB) {
  ReceiverPayload payload{};
  EncodeQuaternion(q, &payload);
  for (int i = 16; i < kReceiverPayloadBytes; ++i) payload[i] = extra;
  return FormatReceiverLine(sensor, flag, payload);
}

const Quaternion kQ1{0.996276, 0.078654, 0.007692, 0.034479};
const Quaternion kQ2{0.967565, 0.015171, -0.011132, 0.251919};

TEST_CASE("Receiver line layout follows the central's printf", "[io][receiver]") {
  // w = 1.0f is 0x3f800000, little-endian 00 00 80 3f.
  const std::string line = Line(2, NewDataFlag::kFresh, {1, 0, 0, 0}, 0x11);
  CHECK(line.size() == 54);
  CHECK(line.substr(0, 12) == "02010000803f");
  CHECK(line.substr(36) == "111111111111111111");
}

TEST_CASE("Receiver capture: frames, stale and never rows", "[io][receiver]") {
  // Three frames of sensors 1..3. Sensor 3 never connects; sensor 2 is stale in frame 2.
  std::string text;
  text += Line(1, NewDataFlag::kFresh, kQ1) + "\r\n";
  text += Line(2, NewDataFlag::kFresh, kQ2) + "\r\n";
  text += Line(3, NewDataFlag::kNever, {0, 0, 0, 0}) + "\r\n";
  text += Line(1, NewDataFlag::kFresh, kQ1) + "\n";
  text += Line(2, NewDataFlag::kStale, kQ2) + "\n";
  text += Line(3, NewDataFlag::kNever, {0, 0, 0, 0}) + "\n";
  text += Line(1, NewDataFlag::kFresh, kQ1) + "\n";
  text += Line(2, NewDataFlag::kFresh, kQ2) + "\n";
  text += Line(3, NewDataFlag::kNever, {0, 0, 0, 0}) + "\n";
  TempFile file(text, ".txt");
  auto r = LoadSession(file.path());
  REQUIRE(r.ok());
  const Session& s = r.value();
  CHECK(s.format == SessionFormat::kReceiver);
  CHECK(s.rows == 9);
  REQUIRE(s.tags.size() == 3);
  const Tag& t1 = s.tags[0];
  const Tag& t2 = s.tags[1];
  const Tag& t3 = s.tags[2];
  CHECK(t1.counts.frames == 3);
  CHECK(t1.counts.fresh == 3);
  CHECK(t2.counts.fresh == 2);
  CHECK(t2.counts.stale == 1);
  CHECK(t2.counts.PacketLossRatio() == Approx(1.0 / 3.0));
  CHECK(t3.counts.never == 3);
  CHECK(t3.size() == 0);
  // (stale + never) / frames: a tag that never connected has lost every frame.
  CHECK(t3.counts.PacketLossRatio() == 1.0);
  // Stale rows are not observations: sensor 2 has frames 0 and 2 only.
  REQUIRE(t2.size() == 2);
  CHECK(t2.t_s[0] == 0.0);
  CHECK(t2.t_s[1] == Approx(2 * 3281.0 / 32768.0));
  CHECK(t2.line[1] == 8);
  // Quaternions are float32 on the wire; Euler angles as in thesis Listing 1.
  CHECK(t1.Find("qw")->values[0] == static_cast<double>(static_cast<float>(kQ1.w)));
  CHECK(t1.Find("yaw_deg")->values[0] == Approx(4.009102).margin(5e-4));
  CHECK(t2.Find("yaw_deg")->values[0] == Approx(29.167585).margin(5e-4));
  CHECK(t1.text_columns.at(0).name == "payload_hex");
  CHECK(t1.text_columns.at(0).values[0] == "ababababababababab");
}

TEST_CASE("Receiver load progress adds up to the file size", "[io][receiver]") {
  std::string text = "# capture\n";
  for (int i = 0; i < 30000; ++i) text += Line(1 + i % 3, NewDataFlag::kFresh, kQ1) + "\r\n";
  text += Line(1, NewDataFlag::kFresh, kQ2);  // No newline at the end.
  TempFile file(text, ".txt");
  LoadOptions options;
  int64_t bytes = 0;
  int calls = 0;
  options.on_bytes_parsed = [&](int64_t n) {
    bytes += n;
    ++calls;
  };
  auto r = LoadSession(file.path(), options);
  REQUIRE(r.ok());
  CHECK(bytes == static_cast<int64_t>(text.size()));
  CHECK(calls == 2);  // ~1.7 MB: one report per MiB of lines, then the rest.
}

TEST_CASE("Receiver frame period is an option", "[io][receiver]") {
  const std::string text =
      Line(1, NewDataFlag::kFresh, kQ1) + "\n" + Line(1, NewDataFlag::kFresh, kQ1) + "\n";
  TempFile file(text, ".txt");
  LoadOptions options;
  options.frame_period_s = 0.25;
  auto r = LoadSession(file.path(), options);
  REQUIRE(r.ok());
  CHECK(r.value().tags[0].t_s[1] == 0.25);
}

std::string ReceiverError(const std::string& text) {
  TempFile file(text, ".txt");
  LoadOptions options;
  options.format = SessionFormat::kReceiver;
  auto r = LoadSession(file.path(), options);
  REQUIRE_FALSE(r.ok());
  Error e = r.error();
  e.file = "capture.txt";
  return e.ToString();
}

TEST_CASE("Receiver bad input: each class is named", "[io][receiver]") {
  const std::string good = Line(1, NewDataFlag::kFresh, kQ1);
  CHECK(ReceiverError(good + "\n" + good.substr(0, 40) + "\n") ==
        "capture.txt:2: receiver line has 40 characters: expected 54 hex characters (sensor, "
        "NewData flag, 25 payload bytes)");
  std::string nonhex = good;
  nonhex[10] = 'g';
  CHECK(ReceiverError(nonhex + "\n") ==
        "capture.txt:1:11: non-hex character 'g' at column 11: expected 0-9 or a-f");
  std::string flag = good;
  flag[2] = '0';
  flag[3] = '7';
  CHECK(ReceiverError(flag + "\n") ==
        "capture.txt:1:3: NewData flag 07: expected 01 (fresh), 00 (stale) or ff (never "
        "received)");
  CHECK(ReceiverError(Line(0, NewDataFlag::kFresh, kQ1) + "\n") ==
        "capture.txt:1:1: sensor number 00: expected a tag number 01..ff");
  CHECK(ReceiverError(Line(1, NewDataFlag::kFresh, {0, 0, 0, 0}) + "\n") ==
        "capture.txt:1:5: fresh row with quaternion norm 0: expected a unit quaternion (w, x, "
        "y, z as float32 little-endian in payload bytes 1..16)");
  CHECK(ReceiverError("") == "capture.txt: empty file: expected receiver capture lines");
}

TEST_CASE("Receiver lenient mode counts bad lines and keeps framing", "[io][receiver]") {
  std::string text = Line(1, NewDataFlag::kFresh, kQ1) + "\n" + "zz\n" +
                     Line(2, NewDataFlag::kFresh, kQ2) + "\n" + Line(1, NewDataFlag::kFresh, kQ1) +
                     "\n";
  TempFile file(text, ".txt");
  LoadOptions options;
  options.lenient = true;
  auto r = LoadSession(file.path(), options);
  REQUIRE(r.ok());
  CHECK(r.value().rejected_rows == 1);
  CHECK(r.value().rejected_lines == std::vector<int64_t>{2});
  CHECK(r.value().tags[0].t_s[1] == Approx(3281.0 / 32768.0));
  CHECK(r.value().tags[1].t_s[0] == 0.0);
}

TEST_CASE("Receiver capture converts to session.csv and back", "[io][receiver]") {
  std::string text;
  for (int frame = 0; frame < 20; ++frame) {
    for (int sensor = 1; sensor <= 3; ++sensor) {
      const Quaternion q = QuaternionFromEuler({frame * 1.5 - 10, sensor * 0.5, -frame * 0.1});
      text += Line(sensor, (frame + sensor) % 7 == 0 ? NewDataFlag::kStale : NewDataFlag::kFresh, q,
                   static_cast<uint8_t>(frame)) +
              "\n";
    }
  }
  TempFile capture(text, ".txt");
  auto first = LoadSession(capture.path());
  REQUIRE(first.ok());
  TempFile csv(FormatSessionCsv(first.value(), false));
  auto second = LoadSession(csv.path());
  REQUIRE(second.ok());
  REQUIRE(second.value().tags.size() == 3);
  for (size_t k = 0; k < 3; ++k) {
    const Tag& a = first.value().tags[k];
    const Tag& b = second.value().tags[k];
    CHECK(a.t_s == b.t_s);
    for (const char* name : {"qw", "qx", "qy", "qz", "yaw_deg", "pitch_deg", "roll_deg"}) {
      CHECK(a.Find(name)->values == b.Find(name)->values);
    }
    CHECK(a.text_columns[0].values == b.text_columns[0].values);
  }
}

}  // namespace
}  // namespace metro
