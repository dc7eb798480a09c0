// Calibration certificate: recovery (residuals shrink after calibration), content that
// ISO/IEC 17025 7.8 asks for, from calibration.json alone (no input reloaded), and bad input.
#include "metro/report/certificate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "metro/calibration/calibration_io.hpp"
#include "metro/core/device_id.hpp"
#include "metro/core/file.hpp"
#include "metro/core/rounding.hpp"
#include "metro/io/session_io.hpp"
#include "metro/report/html_report.hpp"
#include "metro/sim/calibration_session.hpp"
#include "metro/uncertainty/gum.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

struct Fitted {
  SimulatedSession sim;
  Calibration cal;
};

const Fitted& Fit() {
  static const Fitted fitted = [] {
    SimulationOptions so;
    so.seed = 7;
    so.temperature = true;
    so.temp_start_c = 22.0;
    so.temp_end_c = 31.0;
    Fitted f;
    Result<SimulatedSession> sim = SimulateCalibrationSession(so);
    METRO_CHECK(sim.ok());
    f.sim = std::move(sim).value();
    Result<Calibration> cal = CalibrateSessions({&f.sim.session}, CalibrationOptions{});
    METRO_CHECK(cal.ok());
    f.cal = std::move(cal).value();
    return f;
  }();
  return fitted;
}

double Rms(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

TEST_CASE("Static residuals shrink to the noise after calibration", "[report][certificate]") {
  const Fitted& f = Fit();
  const TagCalibration& t = f.cal.tags.front();
  REQUIRE(t.accel);
  REQUIRE(t.gyro);
  // The fit records them (calibration.json's static_residuals), one per static pose it used.
  REQUIRE(t.accel->static_residuals);
  const StaticResiduals& acc = *t.accel->static_residuals;
  CHECK(acc.unit == "g");
  const auto used_static = [](const SensorCalibration& c) {
    return std::count_if(c.segments.begin(), c.segments.end(),
                         [](const Segment& s) { return s.kind == SegmentKind::kStatic && s.used; });
  };
  CHECK(acc.before.size() == static_cast<size_t>(used_static(*t.accel)));
  CHECK(acc.after.size() == acc.before.size());
  // Datasheet tolerances of the simulated truth (+-3 % scale, up to 80 mg offsets) give
  // gravity-norm errors of the order of 10 mg before; after, the pose means carry only the
  // noise of a 3 s pose (400 ug/sqrt(Hz) * sqrt(50 Hz) / sqrt(300) ~ 0.2 mg per axis).
  CHECK(Rms(acc.before) > 5e-3);
  CHECK(Rms(acc.after) < 1e-3);
  REQUIRE(t.gyro->static_residuals);
  const StaticResiduals& gyr = *t.gyro->static_residuals;
  CHECK(gyr.unit == "deg/s");
  CHECK(gyr.before.size() == static_cast<size_t>(used_static(*t.gyro)));
  // Zero-rate offsets up to 20 deg/s before; after, the static rate is the noise.
  CHECK(Rms(gyr.before) > 1.0);
  CHECK(Rms(gyr.after) < 0.05);
  // The first static pose by hand: its raw mean at the nominal 16384 LSB/g (+-2 g), and the
  // calibrated model at its mean temperature, against g_local/g_n = 1.
  const Segment* first = nullptr;
  for (const Segment& s : t.accel->segments) {
    if (s.kind == SegmentKind::kStatic && s.used && first == nullptr) first = &s;
  }
  REQUIRE(first != nullptr);
  const Tag& tag = f.sim.session.tags.front();
  Eigen::Vector3d raw = Eigen::Vector3d::Zero();
  double temp_c = 0.0;
  for (size_t i = first->begin; i < first->end; ++i) {
    raw += Eigen::Vector3d(tag.Find("ax_lsb")->values[i], tag.Find("ay_lsb")->values[i],
                           tag.Find("az_lsb")->values[i]);
    temp_c += tag.Find("temp_c")->values[i];
  }
  raw /= static_cast<double>(first->end - first->begin);
  temp_c /= static_cast<double>(first->end - first->begin);
  CHECK(acc.before[0] == Approx((raw / 16384.0).norm() - 1.0).epsilon(1e-12));
  CHECK(acc.after[0] == Approx(t.accel->model.Apply(raw, temp_c).norm() - 1.0).epsilon(1e-9));
  // A raw calibration without its full-scale setting has no nominal sensitivity.
  SensorCalibration no_scale = *t.accel;
  no_scale.full_scale.reset();
  Result<StaticResiduals> none = ComputeStaticResiduals(no_scale, {&tag}, 9.80665);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message ==
        "static residuals: the full-scale setting of the raw (LSB) input is not set");
}

TEST_CASE("Certificate states identification results with U and k and conditions",
          "[report][certificate]") {
  const Fitted& f = Fit();
  Result<std::string> html = RenderCalibrationCertificate(f.cal);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  CHECK(h.find("<title>Calibration certificate</title>") != std::string::npos);
  for (const char* section :
       {"1. Identification", "2. Method and model", "3. Results", "4. Conditions", "5. Validity"}) {
    INFO(section);
    CHECK(h.find(section) != std::string::npos);
  }
  CHECK(h.find(f.sim.session.sha256) != std::string::npos);
  // U = k u of b0_x, rounded per GUM 7.2.6, k = t_0.975 at the fit's dof (1.96 when the
  // accelerometer's u rests on the poses' noise alone).
  const TagCalibration& t = f.cal.tags.front();
  const double k = t.accel->coverage_factor_95 == 1.959963984540054
                       ? 1.959963984540054
                       : CoverageFactor(0.95, t.accel->dof);
  const RoundedResult r = RoundForStatement(t.accel->model.bias[0], k * t.accel->bias_u[0]);
  CHECK(h.find("<td>bias b0_x</td><td>LSB</td><td class=\"num\">" + r.value + "</td>") !=
        std::string::npos);
  // The temperature range of the record, from the simulated ramp 22 -> 31 degC.
  const Quantity* temp = f.sim.session.tags.front().Find("temp_c");
  REQUIRE(temp != nullptr);
  const double lo = *std::min_element(temp->values.begin(), temp->values.end());
  const double hi = *std::max_element(temp->values.begin(), temp->values.end());
  CHECK(lo == Approx(22.0).margin(0.1));
  CHECK(hi == Approx(31.0).margin(0.1));
  char range[64];
  std::snprintf(range, sizeof range, "%.2f .. %.2f degC", lo, hi);
  CHECK(h.find(range) != std::string::npos);
  // Before/after residual plots for both sensors.
  CHECK(std::count(h.begin(), h.end(), '\n') > 0);
  size_t svgs = 0;
  for (size_t at = h.find("<svg"); at != std::string::npos; at = h.find("<svg", at + 1)) ++svgs;
  CHECK(svgs == 2);
  CHECK(h.find("http") == std::string::npos);
}

std::string Unescape(std::string h);  // Below.
std::string Between(const std::string& h, const std::string& open, const std::string& close);

TEST_CASE("Certificate from calibration.json needs no input record", "[report][certificate]") {
  const Fitted& f = Fit();
  // calibration.json naming a record that is nowhere on disk: the page is the same, since the
  // conditions and residuals are in the file (record_conditions, static_residuals).
  Calibration cal = f.cal;
  cal.inputs.front().path = "/nonexistent/session.csv";
  testing::TempFile json(FormatCalibrationJson(cal), ".json");
  Result<std::string> html = RenderJsonFileHtml(json.path());
  REQUIRE(html.ok());
  const std::string h = Unescape(html.value());
  CHECK(h.find("as computed from the input records by the fit") != std::string::npos);
  const RecordConditions& r = cal.tags.front().record_conditions->front();
  REQUIRE(r.temp_min_c);
  CHECK(h.find(fmt::format("<td><code>/nonexistent/session.csv</code></td><td class=\"num\">{}"
                           "</td><td class=\"num\">{:.1f} s</td><td>{:.2f} .. {:.2f} degC</td>",
                           r.samples, r.duration_s, *r.temp_min_c, *r.temp_max_c)) !=
        std::string::npos);
  size_t svgs = 0;
  for (size_t at = h.find("<svg"); at != std::string::npos; at = h.find("<svg", at + 1)) ++svgs;
  CHECK(svgs == 2);
  // The static poses' temperatures come from calibration.json too.
  const PoseTemperatureRange& poses = *f.cal.tags.front().accel->static_pose_temperature;
  CHECK(poses.min_c > 22.0);
  CHECK(poses.max_c < 31.0);
  CHECK(h.find(fmt::format("sensor 1: the {} static poses were at {:.2f} .. {:.2f} degC",
                           poses.poses, poses.min_c, poses.max_c)) != std::string::npos);
}

TEST_CASE("Certificate of a calibration.json from before the fit recorded its records",
          "[report][certificate]") {
  // The golden file has neither record_conditions nor static_residuals: it loads, and its page
  // says what is missing and how to get it, with no plot and no invented temperature range.
  const std::string golden =
      std::string(METRO_SOURCE_DIR) + "/datasets/golden/calibration_sensor2.json";
  Result<Calibration> cal = LoadCalibration(golden);
  REQUIRE(cal.ok());
  CHECK_FALSE(cal.value().tags.front().record_conditions);
  CHECK_FALSE(cal.value().tags.front().accel->static_residuals);
  Result<std::string> html = RenderJsonFileHtml(golden);
  REQUIRE(html.ok());
  const std::string h = Unescape(html.value());
  CHECK(h.find("This calibration.json was written before metro recorded the records' conditions "
               "and the static residuals at fit time") != std::string::npos);
  CHECK(h.find("Residuals before/after calibration: not in this calibration.json (written "
               "before metro recorded them at fit time); re-run `calibrate fit` on the input "
               "records to get them") != std::string::npos);
  CHECK(h.find("The temperature range of the records is not stated") != std::string::npos);
  CHECK(h.find("<svg") == std::string::npos);
  // No row in the conditions table (its header only).
  const std::string conditions = Between(h, "<section id=\"conditions\">", "</section>");
  REQUIRE_FALSE(conditions.empty());
  CHECK(conditions.find("<td") == std::string::npos);
}

// The page's text with mustache's HTML escapes of ' " & undone.
std::string Unescape(std::string h) {
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"&apos;", "'"}, {"&quot;", "\""}, {"&amp;", "&"}}) {
    for (size_t at = h.find(from); at != std::string::npos; at = h.find(from, at + to.size())) {
      h.replace(at, from.size(), to);
    }
  }
  return h;
}

// The y coordinates of the markers of one colour in the first plot of the page (PLplot's svg
// device draws each point marker as a <text> glyph placed by its transform matrix).
std::vector<double> MarkerYs(const std::string& h, const std::string& fill) {
  const size_t a = h.find("<svg"), b = h.find("</svg>", a);
  const std::string svg = h.substr(a, b - a);
  const std::regex marker("<text[^>]*fill=\"" + fill +
                          "\"[^>]*transform=\"matrix\\([^)]* ([-0-9.]+)\\)\"");
  std::vector<double> ys;
  for (std::sregex_iterator it(svg.begin(), svg.end(), marker), end; it != end; ++it) {
    ys.push_back(std::stod((*it)[1].str()));
  }
  std::sort(ys.begin(), ys.end());
  return ys;
}

// The text between `open` and the next `close` after it, or "" when absent.
std::string Between(const std::string& h, const std::string& open, const std::string& close) {
  const size_t a = h.find(open);
  if (a == std::string::npos) return "";
  const size_t b = h.find(close, a + open.size());
  return b == std::string::npos ? "" : h.substr(a + open.size(), b - a - open.size());
}

// The calibration as `calibrate report` reads it: written to JSON and read back.
Calibration ThroughJson(const Calibration& cal) {
  Result<Calibration> back = CalibrationFromJson(FormatCalibrationJson(cal), "cal.json");
  METRO_CHECK(back.ok());
  return std::move(back).value();
}

TEST_CASE("Certificate identifies the item from calibration.json and the tags file",
          "[report][certificate]") {
  Calibration cal = Fit().cal;
  cal.tags.front().device_id = 0x9ABCDEF012345678ull;
  cal.tags.front().name = "Chest";
  cal.tags.front().profile = "mpu6050";
  cal = ThroughJson(cal);
  Result<std::string> html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string items = Unescape(Between(html.value(), "<table id=\"items\">", "</table>"));
  REQUIRE_FALSE(items.empty());
  // The device ID as calibration.json states it, and in nrfjprog's word order.
  const nlohmann::json j = nlohmann::json::parse(FormatCalibrationJson(cal));
  const std::string id = j["tags"][0]["device_id"].get<std::string>();
  CHECK(id == "9ABCDEF012345678");
  CHECK(items.find("<td class=\"hash device-id\">" + id) != std::string::npos);
  CHECK(items.find("nrfjprog order 12345678 9ABCDEF0") != std::string::npos);
  CHECK(items.find("<td>Chest</td>") != std::string::npos);
  CHECK(items.find("InvenSense MPU6050 (profile mpu6050 declared in the tags file)") !=
        std::string::npos);
  // The simulated session is session.csv of raw counts: the unit, the full scale the fit
  // used (calibration.json's full_scale) and the source, no guess.
  REQUIRE(j["tags"][0]["accel"]["full_scale"] == 2.0);
  REQUIRE(j["tags"][0]["gyro"]["full_scale"] == 250.0);
  CHECK(items.find("accelerometer (input LSB, raw counts; the fit's nominal sensitivity at +-2 g "
                   "full scale) and gyroscope (input LSB, raw counts; the fit's nominal "
                   "sensitivity at +-250 deg/s full scale)") != std::string::npos);
  CHECK(items.find("session.csv") != std::string::npos);

  // Without a tags file (and a file from before full_scale was recorded): no name, no
  // device ID, no IMU type or full scale invented.
  cal.tags.front().accel->full_scale.reset();
  cal.tags.front().device_id.reset();
  cal.tags.front().name.clear();
  cal.tags.front().profile.clear();
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string bare = Between(html.value(), "<table id=\"items\">", "</table>");
  CHECK(bare.find("<td class=\"hash device-id\">not stated</td>") != std::string::npos);
  CHECK(bare.find("<td>not stated</td>") != std::string::npos);
  CHECK(bare.find("MPU6050") == std::string::npos);
  CHECK(bare.find("IMU type not declared") != std::string::npos);
  CHECK(bare.find("accelerometer (input LSB, raw counts; full-scale setting not recorded in "
                  "calibration.json)") != std::string::npos);

  // An imu_tk record (e.g. imu_tk's Xsens pair) is never called an MPU6050 either.
  cal.inputs.front().format = "imutk";
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string imutk = Between(html.value(), "<table id=\"items\">", "</table>");
  CHECK(imutk.find("MPU6050") == std::string::npos);
  CHECK(imutk.find("imu_tk accelerometer + gyroscope file pair") != std::string::npos);
  // The receiver's hex lines come only from metro's tags: that much the data say.
  cal.inputs.front().format = "receiver";
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  CHECK(Between(html.value(), "<table id=\"items\">", "</table>")
            .find("MPU6050 on an nRF51802 BLE tag (receiver capture; no profile declared)") !=
        std::string::npos);
}

TEST_CASE("Certificate states k and dof per sensor as calibration.json gives them",
          "[report][certificate]") {
  const Calibration cal = ThroughJson(Fit().cal);
  Result<std::string> html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string h = Unescape(html.value());
  const nlohmann::json j = nlohmann::json::parse(FormatCalibrationJson(cal));
  const nlohmann::json& gyro = j["tags"][0]["gyro"];
  const int dof = gyro["dof"].get<int>();
  REQUIRE(dof >= 1);
  // JCGM 100:2008 G.3.2: k = t_0.975(dof); the file's coverage_factor_95 is the same number.
  const double k = gyro["coverage_factor_95"].get<double>();
  CHECK(CoverageFactor(0.95, dof) == Approx(k).epsilon(1e-12));
  CHECK(h.find(fmt::format("k = t_0.975({}) = {:.4g} (Student's t at the fit's {} degrees of "
                           "freedom, JCGM 100:2008 G.3.2)",
                           dof, k, dof)) != std::string::npos);
  CHECK(h.find(fmt::format("<td class=\"num coverage-k\">{:.4g}</td>", k)) != std::string::npos);
  // The gyroscope's U of b0_x is that k times u.
  const double b = gyro["bias"][0].get<double>(), u = gyro["bias_u"][0].get<double>();
  const RoundedResult r = RoundForStatement(b, k * u);
  CHECK(h.find("<td>bias b0_x</td><td>LSB</td><td class=\"num\">" + r.value +
               "</td><td class=\"num\">" + RoundForStatement(b, u).uncertainty +
               "</td><td class=\"num\">" + r.uncertainty + "</td>") != std::string::npos);
  // dof < 1: no k, so no U; u is still stated.
  Calibration none = cal;
  none.tags.front().gyro->dof = 0;
  none.tags.front().gyro->coverage_factor_95 = 0.0;
  html = RenderCalibrationCertificate(none);
  REQUIRE(html.ok());
  CHECK(html.value().find("no coverage factor: the fit has 0 degrees of freedom") !=
        std::string::npos);
  CHECK(html.value().find("<td class=\"num\">not stated</td>") != std::string::npos);
}

TEST_CASE("Certificate states the gravity value with its source", "[report][certificate]") {
  Calibration cal = Fit().cal;
  CHECK(cal.gravity_source == "standard");  // CalibrationOptions default, not given.
  cal = ThroughJson(cal);
  Result<std::string> html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  CHECK(Between(html.value(), "<td id=\"gravity\">", "</td>") ==
        "9.80665 m/s^2, standard gravity g_n (conventional value, 3rd CGPM 1901), not a "
        "measured local gravity");
  CHECK(html.value().find("Accelerometer: referred to standard gravity 9.80665 m/s^2") !=
        std::string::npos);

  cal.gravity_mps2 = 9.81744;
  cal.gravity_source = "given";
  cal = ThroughJson(cal);
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  CHECK(Between(html.value(), "<td id=\"gravity\">", "</td>") ==
        "9.81744 m/s^2, given: calibrate fit --gravity-mps2 9.81744");
  CHECK(html.value().find("traceable only to the gravity value 9.81744 m/s^2 given by the user") !=
        std::string::npos);

  // A file written before the source was recorded says so.
  cal.gravity_source.clear();
  html = RenderCalibrationCertificate(ThroughJson(cal));
  REQUIRE(html.ok());
  CHECK(Between(html.value(), "<td id=\"gravity\">", "</td>") ==
        "9.81744 m/s^2 (source not recorded in calibration.json)");
}

TEST_CASE("Certificate states the dates of measurement from the records", "[report][certificate]") {
  Calibration cal = Fit().cal;
  // The simulated record's times are relative: its span, no date.
  REQUIRE(cal.inputs.size() == 1);
  const std::vector<double>& t = Fit().sim.session.tags.front().t_s;
  REQUIRE(cal.inputs[0].duration_s);
  CHECK(*cal.inputs[0].duration_s == t.back() - t.front());
  CHECK(cal.inputs[0].start_utc.empty());
  Result<std::string> html = RenderCalibrationCertificate(ThroughJson(cal));
  REQUIRE(html.ok());
  CHECK(Between(html.value(), "<td id=\"measurement-dates\">", "</td>") ==
        "1 record(s) with relative times only (a clock since the start, no date): measured on "
        "or before the fit, " +
            cal.date_utc);
  CHECK(html.value().find(fmt::format("<td class=\"num\">{:.1f} s</td>", t.back() - t.front())) !=
        std::string::npos);

  // A record with a Unix clock: its first and last observation, distinct from the issue date.
  cal.inputs[0].start_utc = "2026-01-01T00:00:00Z";
  cal.inputs[0].end_utc = "2026-01-01T01:00:00Z";
  html = RenderCalibrationCertificate(ThroughJson(cal));
  REQUIRE(html.ok());
  CHECK(Unescape(Between(html.value(), "<td id=\"measurement-dates\">", "</td>")) ==
        "2026-01-01T00:00:00Z .. 2026-01-01T01:00:00Z (UTC, from the records' time columns)");
}

TEST_CASE("Record time span is a date only for a Unix clock", "[report][certificate]") {
  Session s;
  s.format = SessionFormat::kSensorLogger;
  Tag tag;
  tag.t_s = {0.0, 1800.0, 3600.75};
  s.tags.push_back(tag);
  s.input.time_integer = true;
  s.input.time_origin_ns = 1767225600LL * 1000000000LL;  // date -d @1767225600: 2026-01-01 UTC
  InputFile in = RecordTimeSpan(s);
  CHECK(in.format == "sensorlogger");
  REQUIRE(in.duration_s);
  CHECK(*in.duration_s == 3600.75);
  CHECK(in.start_utc == "2026-01-01T00:00:00Z");
  CHECK(in.end_utc == "2026-01-01T01:00:00Z");
  // A clock since power-on (origin 1 s): no date.
  s.input.time_origin_ns = 1000000000LL;
  in = RecordTimeSpan(s);
  CHECK(in.start_utc.empty());
  CHECK(in.end_utc.empty());
  CHECK(*in.duration_s == 3600.75);
  // Epoch seconds in a t_s column are a date too.
  s.input.time_integer = false;
  s.tags.front().t_s = {1767225600.0, 1767225610.0};
  in = RecordTimeSpan(s);
  CHECK(in.start_utc == "2026-01-01T00:00:00Z");
  CHECK(in.end_utc == "2026-01-01T00:00:10Z");
}

TEST_CASE("Certificate has a traceability statement print CSS and log residual plots",
          "[report][certificate]") {
  const Fitted& f = Fit();
  Result<std::string> html = RenderCalibrationCertificate(f.cal);
  REQUIRE(html.ok());
  const std::string& h = html.value();
  CHECK(h.find("<h3 id=\"traceability\">Metrological traceability</h3>") != std::string::npos);
  CHECK(h.find("No further link to the SI is claimed") != std::string::npos);
  // The gyroscope's references as its residual groups in calibration.json record them.
  const nlohmann::json j = nlohmann::json::parse(FormatCalibrationJson(f.cal));
  int table = 0, rotation = 0;
  for (const nlohmann::json& g : j["tags"][0]["gyro"]["residual_groups"]) {
    if (g["kind"] == "table_rate") table += g["count"].get<int>();
    if (g["kind"] == "rotation_gravity") rotation += g["count"].get<int>();
  }
  CHECK(rotation > 0);
  CHECK((h.find("rotation-table rates recorded in the records (table_rate_dps)") !=
         std::string::npos) == (table > 0));
  CHECK(h.find("to the angle between the gravity directions of consecutive static poses") !=
        std::string::npos);
  // Print: tables whole on a page, numbered pages carrying the certificate id.
  CHECK(h.find("table, figure, tr, .keep { break-inside: avoid;") != std::string::npos);
  CHECK(h.find("content: \"page \" counter(page) \" of \" counter(pages);") != std::string::npos);
  CHECK(h.find("content: \"Calibration certificate " + CalibrationCertificateId(f.cal) + "\";") !=
        std::string::npos);
  // The residual plots are drawn on a log axis of |residual|. The accelerometer's residuals
  // after calibration are about 1e-4 g, spread over about a decade, and those before about
  // 1e-2 g: on a linear axis (0 .. 0.1 g over ~280 px) the after markers' interquartile range
  // would be under 1 px, on the log axis (about 5 decades) it is tens of px.
  const std::vector<double> after = MarkerYs(h, "#1F77B4");
  REQUIRE(after.size() > 8);
  const double iqr_px = after[after.size() * 3 / 4] - after[after.size() / 4];
  CHECK(iqr_px > 10.0);
  CHECK(h.find("on a logarithmic axis") != std::string::npos);
}

TEST_CASE("Certificate bad input is refused with a message", "[report][certificate]") {
  const Fitted& f = Fit();
  CertificateOptions o;
  o.coverage_probability = 1.5;
  Result<std::string> r = RenderCalibrationCertificate(f.cal, o);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "certificate: coverage probability p = 1.5 is outside (0, 1)");
  // A calibration.json that is not one is refused at the offending value.
  testing::TempFile bad("{\n  \"schema\": \"metro.calibration/1\",\n  \"gravity_mps2\": true\n}\n",
                        ".json");
  r = RenderJsonFileHtml(bad.path());
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString() == bad.path() + ":3:19: gravity_mps2: expected a number, found true");
}

// Issue #36 point 7: the k stated comes from the dof it names. A u that claims to rest on the
// poses' noise (coverage_factor_95 1.96) while the residuals are 4 times that noise (7 dof,
// reduced chi-square 15.7) gets Student's t at those 7 dof, and the text names them.
TEST_CASE("Certificate: k comes from the dof it names, gravity's u is in U",
          "[report][certificate]") {
  Calibration cal = ThroughJson(Fit().cal);
  SensorCalibration& a = *cal.tags.front().accel;
  a.dof = 7;
  a.reduced_chi2 = 15.7;
  a.coverage_factor_95 = 1.959963984540054;
  Result<std::string> html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string h = Unescape(html.value());
  const double t7 = 2.364624251592785;  // t_0.975(7), tables of Student's t.
  CHECK(CoverageFactor(0.95, 7.0) == Approx(t7).epsilon(1e-9));
  CHECK(h.find(fmt::format("k = t_0.975(7) = {:.4g} (Student's t at the fit's 7 degrees of "
                           "freedom",
                           t7)) != std::string::npos);
  CHECK(h.find(fmt::format("<td class=\"num coverage-k\">{:.4g}</td>", t7)) != std::string::npos);
  CHECK(h.find("k = t_0.975(inf)") == std::string::npos);
  // With residuals that agree with the noise, infinite dof, named as such.
  a.reduced_chi2 = 1.1;
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  CHECK(Unescape(html.value()).find("k = t_0.975(inf) = 1.96") != std::string::npos);
  CHECK(Unescape(html.value()).find("accel: k = 1.96 at infinite degrees of freedom") !=
        std::string::npos);
  // Gravity: standard gravity stands for a local value within +-0.03 m/s^2, rectangular: the
  // scale factor's u is sqrt(u_fit^2 + (k u_g / g)^2), u_g = 0.03 / sqrt(3).
  cal.gravity_source = "standard";
  cal.gravity_u_mps2.reset();
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  const std::string g = Unescape(html.value());
  const double u_g = 0.03 / std::sqrt(3.0);
  const double u_k = std::hypot(a.scale_u[0], a.model.scale[0] * u_g / cal.gravity_mps2);
  CHECK(u_k > 3 * a.scale_u[0]);  // The gravity term dominates the fit's own.
  CHECK(g.find("<td>scale k_x</td><td>g/LSB</td><td class=\"num\">" +
               RoundForStatement(a.model.scale[0], 1.96 * u_k).value + "</td><td class=\"num\">" +
               RoundForStatement(a.model.scale[0], u_k).uncertainty) != std::string::npos);
  CHECK(g.find("u(g) = 0.0173 m/s^2: standard gravity") != std::string::npos);
  // A stated u(g) replaces the assumption.
  cal.gravity_u_mps2 = 1e-5;
  html = RenderCalibrationCertificate(cal);
  REQUIRE(html.ok());
  CHECK(Unescape(html.value()).find("u(g) = 1e-05 m/s^2 as stated") != std::string::npos);
}

TEST_CASE("Certificate refuses model_rejected constants unless accepted, and says so",
          "[report][certificate]") {
  Calibration cal = ThroughJson(Fit().cal);
  ModelCheck m;
  m.selection = "given";
  m.status = "rejected";
  m.model_rejected = true;
  m.reason = "the data reject the accelerometer 'bias' model";
  cal.tags.front().accel->model_check = m;
  Result<std::string> html = RenderCalibrationCertificate(cal);
  REQUIRE_FALSE(html.ok());
  CHECK(html.error().kind == ErrorKind::kInput);
  CHECK_THAT(html.error().message, Catch::Contains("model_rejected"));
  CHECK_THAT(html.error().message, Catch::Contains("--accept-rejected-model"));
  CertificateOptions o;
  o.accept_rejected_model = true;
  html = RenderCalibrationCertificate(cal, o);
  REQUIRE(html.ok());
  CHECK(Unescape(html.value()).find("stated only because --accept-rejected-model was given") !=
        std::string::npos);
  CHECK(Unescape(html.value())
            .find("Stated with --accept-rejected-model although marked "
                  "model_rejected: sensor") != std::string::npos);
}

TEST_CASE("A view of calibration.json shows model_rejected constants under a banner",
          "[report][certificate]") {
  Calibration cal = ThroughJson(Fit().cal);
  CertificateOptions view;
  view.view = true;
  // Without rejected constants the view is the certificate.
  Result<std::string> html = RenderCalibrationCertificate(cal, view);
  REQUIRE(html.ok());
  CHECK(html.value().find("<title>Calibration certificate</title>") != std::string::npos);
  CHECK(html.value().find("model-rejected") == std::string::npos);
  ModelCheck m;
  m.selection = "given";
  m.status = "rejected";
  m.model_rejected = true;
  m.reason = "the data reject the accelerometer 'bias' model";
  cal.tags.front().accel->model_check = m;
  html = RenderCalibrationCertificate(cal, view);
  REQUIRE(html.ok());
  const std::string page = Unescape(html.value());
  CHECK(page.find("<title>Calibration report (not a certificate)</title>") != std::string::npos);
  const size_t banner = page.find("Not a certificate: constants marked model_rejected");
  REQUIRE(banner != std::string::npos);
  CHECK(banner < page.find("1. Identification"));
  CHECK(page.find("<b>sensor " + std::to_string(cal.tags.front().sensor) + " accelerometer</b> ('" +
                  ModelKindName(cal.tags.front().accel->model.kind) +
                  "' model, rejected): the data reject the accelerometer 'bias' model") !=
        std::string::npos);
  CHECK(page.find("These constants are marked model_rejected and are not certified") !=
        std::string::npos);
  CHECK(page.find("Not certified (marked model_rejected; this page is a view, not a "
                  "certificate): sensor") != std::string::npos);
  CHECK(page.find("Calibration certificate") == std::string::npos);
}
}  // namespace
}  // namespace metro
