// The rotation-table simulator: schedule, error model and file layouts.
#include "metro/sim/table_session.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

#include "metro/core/angles.hpp"
#include "metro/io/session_io.hpp"
#include "support/session_text.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

using testing::Into;
using testing::TempFile;

TEST_CASE("Table simulator schedule and error model", "[sim][accuracy]") {
  TableSimulationOptions o;  // 0..330 by 30, two up-and-down sweeps
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  // 12 angles up, 11 down, then 11 up and 11 down again.
  REQUIRE(truth.plateaus.size() == 12 + 11 + 11 + 11);
  CHECK(truth.plateaus[0].direction == 0);
  CHECK(truth.plateaus[11].reference_deg == 330.0);
  CHECK(truth.plateaus[11].direction == 1);
  CHECK(truth.plateaus[12].reference_deg == 300.0);
  CHECK(truth.plateaus[12].direction == -1);
  CHECK(truth.plateaus[22].reference_deg == 0.0);
  CHECK(truth.plateaus[23].direction == 1);
  // Dwell 20 s; a 30 deg step at 20 deg/s takes 1.5 s.
  CHECK(truth.plateaus[1].t_start_s == Approx(21.5));
  CHECK(truth.plateaus[1].t_end_s == Approx(41.5));
  // Closed form at 90 deg, reached turning up:
  // 0.5 + 0.002 * 90 + 0.3 cos 90 - 0.2 sin 90 + 0.15 / 2 = 0.555 deg.
  CHECK(TableErrorModelDeg(o, 90.0, 1) == Approx(0.555).margin(1e-12));
  CHECK(TableErrorModelDeg(o, 90.0, -1) == Approx(0.405).margin(1e-12));
  CHECK(text.size() < 1000000);
}

TEST_CASE("Noise-free table session carries theta plus the error", "[sim][accuracy]") {
  TableSimulationOptions o;
  o.noise_std_deg = 0.0;
  o.quantization_deg = 0.0;
  o.packet_loss = 0.0;
  o.sweeps = 1;
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  TempFile file(text);
  auto loaded = LoadSession(file.path());
  REQUIRE(loaded.ok());
  const Tag& tag = loaded.value().tags.at(0);
  CHECK(tag.sensor == 2);
  const Quantity* table = tag.Find("table_angle_deg");
  const Quantity* yaw = tag.Find("yaw_deg");
  const Quantity* pitch = tag.Find("pitch_deg");
  REQUIRE(table != nullptr);
  REQUIRE(yaw != nullptr);
  int checked = 0;
  for (const TablePlateauTruth& p : truth.plateaus) {
    // Last observation of the plateau: the 0.3 s lag has decayed completely.
    size_t k = 0;
    while (k + 1 < tag.size() && tag.t_s[k + 1] < p.t_end_s) ++k;
    CHECK(table->values[k] == Approx(p.reference_deg).margin(1e-9));
    CHECK(WrapDeg180(yaw->values[k] - p.reference_deg - p.error_deg) == Approx(0.0).margin(1e-4));
    // Mounting tilt on pitch: base 1 deg + 0.4 sin(theta).
    CHECK(pitch->values[k] ==
          Approx(1.0 + 0.4 * std::sin(p.reference_deg * M_PI / 180.0)).margin(1e-4));
    ++checked;
  }
  CHECK(checked == 23);
}

TEST_CASE("Table simulator writes a receiver capture with a separate reference log",
          "[sim][accuracy]") {
  TableSimulationOptions o;
  o.sweeps = 1;
  o.reference_clock_offset_s = 2.5;
  std::string capture, reference;
  REQUIRE(SimulateTableSession(o, SessionFormat::kReceiver, Into(&capture), Into(&reference)).ok());
  CHECK(capture.substr(0, 2) == "02");
  CHECK(capture.find("table") == std::string::npos);
  TempFile ref_file(reference);
  auto ref = LoadSession(ref_file.path());
  REQUIRE(ref.ok());
  const Tag& r = ref.value().tags.at(0);
  REQUIRE(r.Find("table_angle_deg") != nullptr);
  CHECK(r.t_s.front() == Approx(2.5));
  CHECK(r.t_s[1] - r.t_s[0] == Approx(0.05));

  std::string ignored;
  Status no_reference = SimulateTableSession(o, SessionFormat::kReceiver, Into(&ignored));
  REQUIRE(!no_reference.ok());
  CHECK(no_reference.error().message ==
        "a receiver capture has no table column: give a reference log to write");
}

TEST_CASE("The table turns at the table rate between plateaus", "[sim][accuracy]") {
  // 0..90 by 30 at 10 deg/s: each move takes 3 s; the readout ramps linearly through it.
  TableSimulationOptions o;
  o.end_deg = 90.0;
  o.sweeps = 1;
  o.dwell_s = 5.0;
  o.move_rate_dps = 10.0;
  o.packet_loss = 0.0;
  o.rate_hz = 10.0;
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  REQUIRE(truth.plateaus.size() == 7);
  CHECK(truth.plateaus[1].t_move_s == Approx(5.0));
  CHECK(truth.plateaus[1].t_start_s == Approx(8.0));
  TempFile file(text);
  auto loaded = LoadSession(file.path());
  REQUIRE(loaded.ok());
  const Tag& tag = loaded.value().tags.at(0);
  const Quantity* table = tag.Find("table_angle_deg");
  REQUIRE(table != nullptr);
  int moving = 0;
  for (size_t k = 0; k < tag.size(); ++k) {
    const double t = tag.t_s[k];
    if (t > 5.0 && t < 8.0) {
      // Closed form of the ramp: 10 deg/s from 0 deg at t = 5 s.
      CHECK(table->values[k] == Approx(10.0 * (t - 5.0)).margin(1e-3));
      ++moving;
    }
  }
  CHECK(moving >= 28);
  // The rest of a plateau is the dwell alone (5 s), never the dwell plus the move.
  CHECK(truth.plateaus[2].t_end_s - truth.plateaus[2].t_start_s == Approx(5.0));
}

TEST_CASE("Table truth sidecar JSON and a wrapped readout", "[sim][accuracy]") {
  TableSimulationOptions o;
  o.sweeps = 1;
  o.readout_wrap_180 = true;
  o.lag_tau_s = 0.7;
  o.reference_clock_offset_s = 0.1;
  std::string text;
  TableTruth truth;
  REQUIRE(SimulateTableSession(o, SessionFormat::kCsv, Into(&text), nullptr, &truth).ok());
  const auto j = nlohmann::json::parse(TableTruthJson(o, truth));
  CHECK(j["schema"] == "metro.table-truth/1");
  CHECK(j["lag_tau_s"] == 0.7);
  CHECK(j["hysteresis_deg"] == 0.15);
  CHECK(j["offset_deg"] == 0.5);
  CHECK(j["reference_clock_offset_s"] == 0.1);
  CHECK(j["readout_wrap_180"] == true);
  REQUIRE(j["plateaus"].size() == 23);
  // 90 deg reached turning up: 0.5 + 0.18 + 0 - 0.2 + 0.075 = 0.555 deg.
  CHECK(j["plateaus"][3]["reference_deg"] == 90.0);
  CHECK(j["plateaus"][3]["direction"] == "up");
  CHECK(j["plateaus"][3]["error_deg"].get<double>() == Approx(0.555).margin(1e-12));
  CHECK(j["plateaus"][3]["other_axes_deg"][0].get<double>() == Approx(1.4));
  // The readout is signed: 210 deg is written as -150.
  TempFile file(text);
  auto loaded = LoadSession(file.path());
  REQUIRE(loaded.ok());
  const Quantity* table = loaded.value().tags.at(0).Find("table_angle_deg");
  REQUIRE(table != nullptr);
  double lo = 0.0, hi = 0.0;
  int at_minus_150 = 0;
  for (double v : table->values) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    at_minus_150 += std::fabs(v + 150.0) < 1e-9;
  }
  CHECK(lo > -180.0);
  CHECK(hi == Approx(180.0).margin(1e-9));
  CHECK(at_minus_150 > 100);  // Two 20 s plateaus at 210 deg, about 0.1 s apart.
}

TEST_CASE("Table simulator options are validated", "[sim][accuracy]") {
  TableSimulationOptions o;
  std::string why;
  o.axis = TableAxis::kPitch;
  o.start_deg = -60.0;
  o.end_deg = 90.0;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "a pitch table must stay within +-85 deg");
  o.pitch_through_90 = true;
  CHECK(o.IsValid(&why));
  o = TableSimulationOptions();
  o.end_deg = o.start_deg;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "end_deg must be greater than start_deg");
  o = TableSimulationOptions();
  o.sweeps = 0;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "sweeps must be in 1..100");
  auto axis = ParseTableAxis("heading");
  REQUIRE(!axis.ok());
  CHECK(axis.error().message == "unknown table axis 'heading' (expected yaw, pitch or roll)");
  CHECK(ParseTableAxis("roll").value() == TableAxis::kRoll);
}

}  // namespace
}  // namespace metro
