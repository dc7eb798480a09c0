#include "metro/report/plot_data.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numeric>
#include <random>
#include <string>

#include "core/json_reader.hpp"
#include "core/json_text.hpp"
#include "report/plot_data_json.hpp"

namespace metro {
namespace {

// A tag of n observations at 100 Hz with one quantity `values` named "gx_dps".
Tag MakeTag(const std::vector<double>& values) {
  Tag tag;
  tag.sensor = 2;
  for (size_t i = 0; i < values.size(); ++i) tag.t_s.push_back(0.01 * static_cast<double>(i));
  tag.quantities.push_back({"gx_dps", "deg/s", QuantityOrigin::kFile, values});
  return tag;
}

QuantityTypeA Evaluated(const std::vector<double>& values, size_t first, size_t end) {
  QuantityTypeA q;
  q.name = "gx_dps";
  q.unit = "deg/s";
  q.ok = true;
  q.window_begin = first;
  const double n = static_cast<double>(end - first);
  const double mean = std::accumulate(values.begin() + first, values.begin() + end, 0.0) / n;
  double ss = 0.0;
  for (size_t i = first; i < end; ++i) ss += (values[i] - mean) * (values[i] - mean);
  q.type_a.mean = mean;
  q.type_a.std = std::sqrt(ss / (n - 1.0));
  return q;
}

AppliedWindow Window(size_t first, size_t end) {
  AppliedWindow w;
  w.begin = first;
  w.end = end;
  return w;
}

TEST_CASE("plot data: a long record keeps its envelope and the window's bounds", "[report]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<double> v(10000);
  for (double& x : v) x = noise(rng);
  v[4321] = 5.0;   // A spike that any bucket average would lose.
  v[8765] = -4.0;  // And a dip.
  const Tag tag = MakeTag(v);
  PlotDataOptions options;
  options.max_series_points = 100;
  const Result<QuantityPlotData> data = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(500, 9000), Evaluated(v, 500, 9000), options);
  REQUIRE(data.ok());
  const SeriesPlotData& s = data.value().series;
  CHECK(s.t_s.size() <= 100);
  CHECK(s.t_s.size() == s.values.size());
  CHECK(std::is_sorted(s.t_s.begin(), s.t_s.end()));
  CHECK(*std::max_element(s.values.begin(), s.values.end()) == 5.0);
  CHECK(*std::min_element(s.values.begin(), s.values.end()) == -4.0);
  CHECK(s.n_record == 10000);
  CHECK(s.n_window == 8500);
  CHECK(s.window_first_t_s == Approx(5.0));
  REQUIRE(s.window_end_t_s.has_value());
  CHECK(*s.window_end_t_s == Approx(90.0));
  CHECK(s.record_last_t_s == Approx(99.99));

  // The window to the record's end: no end bound.
  const Result<QuantityPlotData> to_end = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(0, 10000), Evaluated(v, 0, 10000), options);
  REQUIRE(to_end.ok());
  CHECK_FALSE(to_end.value().series.window_end_t_s.has_value());
}

TEST_CASE("plot data: quantized data get bins a whole number of steps wide", "[report]") {
  // Angles at the packets' 0.01 deg resolution: no interior bin may be empty.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> draw(12.3, 0.05);
  std::vector<double> v(20000);
  for (double& x : v) x = std::round(draw(rng) * 100.0) / 100.0;
  const Tag tag = MakeTag(v);
  const Result<QuantityPlotData> data = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(0, v.size()), Evaluated(v, 0, v.size()), PlotDataOptions{});
  REQUIRE(data.ok());
  REQUIRE(data.value().histogram.has_value());
  const HistogramPlotData& h = *data.value().histogram;
  CHECK(h.resolution == Approx(0.01));
  CHECK(h.n == 20000);
  CHECK(std::accumulate(h.counts.begin(), h.counts.end(), int64_t{0}) == 20000);
  REQUIRE(h.edges_value.size() == h.counts.size() + 1);
  const double width = h.edges_value[1] - h.edges_value[0];
  const double steps = width / 0.01;
  CHECK(std::fabs(steps - std::round(steps)) < 1e-6);
  CHECK(std::round(steps) >= 1.0);
  // No bin within 3 sigma of the mean is empty (there a bin expects about 18 observations;
  // bins narrower than the lattice would leave every other one empty).
  for (size_t b = 0; b < h.counts.size(); ++b) {
    const double centre = 0.5 * (h.edges_value[b] + h.edges_value[b + 1]);
    if (std::fabs(centre - 12.3) < 3.0 * 0.05) CHECK(h.counts[b] > 0);
  }
  CHECK(h.density_mean == Approx(12.3).margin(0.01));
}

TEST_CASE("plot data: the autocorrelation of an AR(1) record and its white-noise band",
          "[report]") {
  // x_k = phi x_{k-1} + e_k has rho_j = phi^j; with n = 40000 the estimate of rho_1 is within
  // a few times sqrt((1 - phi^2) / n) = 0.003 of phi.
  const double phi = 0.8;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> e(0.0, 1.0);
  std::vector<double> v(40000);
  double x = 0.0;
  for (double& y : v) y = x = phi * x + e(rng);
  const Tag tag = MakeTag(v);
  PlotDataOptions options;
  options.max_autocorrelation_lag = 50;
  const Result<QuantityPlotData> data = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(0, v.size()), Evaluated(v, 0, v.size()), options);
  REQUIRE(data.ok());
  REQUIRE(data.value().autocorrelation.has_value());
  const AutocorrelationPlotData& a = *data.value().autocorrelation;
  REQUIRE(a.rho.size() == 50);
  CHECK(a.rho[0] == Approx(phi).margin(0.015));
  CHECK(a.rho[1] == Approx(phi * phi).margin(0.02));
  CHECK(a.band == Approx(1.96 / 200.0));
  CHECK(a.n == 40000);
}

TEST_CASE("plot data: a constant window has a series but no histogram or autocorrelation",
          "[report]") {
  const std::vector<double> v(100, 1.5);
  const Tag tag = MakeTag(v);
  const Result<QuantityPlotData> data = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(0, 100), Evaluated(v, 0, 100), PlotDataOptions{});
  REQUIRE(data.ok());
  CHECK(data.value().series.t_s.size() == 100);
  CHECK_FALSE(data.value().histogram.has_value());
  CHECK_FALSE(data.value().autocorrelation.has_value());
  // A window beyond the record is refused, not read out of bounds.
  CHECK_FALSE(ComputeQuantityPlotData(tag, tag.quantities[0], Window(0, 101), Evaluated(v, 0, 100),
                                      PlotDataOptions{})
                  .ok());
}

TEST_CASE("plot data: JSON round trip and a wrong value at its position", "[report]") {
  std::vector<double> v(300);
  for (size_t i = 0; i < v.size(); ++i) v[i] = std::sin(0.1 * static_cast<double>(i)) + 0.001 * i;
  const Tag tag = MakeTag(v);
  const Result<QuantityPlotData> data = ComputeQuantityPlotData(
      tag, tag.quantities[0], Window(20, 280), Evaluated(v, 20, 280), PlotDataOptions{});
  REQUIRE(data.ok());
  const std::string text = JsonText(PlotDataToJsonValue(data.value()), 2);
  Result<JsonDocument> document = JsonDocument::Parse(text, "plot.json");
  REQUIRE(document.ok());
  const JsonCursor root(document.value());
  const QuantityPlotData back = PlotDataFromJsonValue(root);
  REQUIRE(root.ok());
  CHECK(JsonText(PlotDataToJsonValue(back), 2) == text);
  CHECK(back.series.values == data.value().series.values);

  // A string among the counts: reported at its own line, with its path.
  const std::string bad = R"({"series": {"n_record": 3, "n_window": 3, "record_first_t_s": 0,
 "record_last_t_s": 0.02, "window_first_t_s": 0, "window_end_t_s": null,
 "t_s": [0, 0.01, 0.02], "values": [1, 2, 3]},
 "histogram": {"n": 3, "resolution": 0, "density_mean": 2, "edges": [0.5, 2, 3.5],
   "counts": [1, "2"]}, "autocorrelation": null})";
  Result<JsonDocument> bad_document = JsonDocument::Parse(bad, "bad.json");
  REQUIRE(bad_document.ok());
  const JsonCursor bad_root(bad_document.value());
  PlotDataFromJsonValue(bad_root);
  REQUIRE_FALSE(bad_root.ok());
  // Line 5 is `   "counts": [1, "2"]}, ...`: the string opens at column 18.
  CHECK(bad_root.error().ToString() ==
        "bad.json:5:18: histogram.counts[1]: expected an integer, found the string \"2\"");
}

TEST_CASE("plot data: JSON that would draw nonsense is refused at its position", "[report]") {
  const std::string series = R"({"series": {"n_record": 3, "n_window": 3, "record_first_t_s": 0,
 "record_last_t_s": 0.02, "window_first_t_s": 0, "window_end_t_s": null,
 "t_s": [0, 0.01, 0.02], "values": [1, 2, 3]},
)";
  auto error_of = [&series](const std::string& rest) {
    Result<JsonDocument> document = JsonDocument::Parse(series + rest, "p.json");
    REQUIRE(document.ok());
    const JsonCursor root(document.value());
    PlotDataFromJsonValue(root);
    return root.ok() ? std::string() : root.error().ToString();
  };
  // Counts that do not add up to n (a division by a wrong n on the page).
  CHECK(error_of(R"( "histogram": {"n": 0, "resolution": 0, "density_mean": 2,
   "edges": [0.5, 2, 3.5], "counts": [0, 0]}, "autocorrelation": null})") ==
        "p.json:4:21: histogram.n: expected the number of observations binned (0), at least 1, "
        "found the number 0");
  // Edges that go back (a bin of negative width).
  CHECK(error_of(R"( "histogram": {"n": 3, "resolution": 0, "density_mean": 2,
   "edges": [0.5, 2, 1.5], "counts": [1, 2]}, "autocorrelation": null})") ==
        "p.json:5:22: histogram.edges[2]: expected edges in increasing order, found the number "
        "1.5");
  // A white-noise band of zero.
  CHECK(error_of(R"( "histogram": null, "autocorrelation": {"n": 3, "band": 0, "rho": [0.5]}})") ==
        "p.json:4:57: autocorrelation.band: expected a band > 0, found the number 0");
  CHECK(error_of(R"( "histogram": null, "autocorrelation": null})").empty());
}

TEST_CASE("plot data: the quantities selected, at most max_quantities of them", "[report]") {
  // Two tags with qw, pitch_deg and gx_dps each: qw is not selected by default, and at most
  // three of the four others get plot data; the fourth is counted as not plotted.
  std::vector<double> v(64);
  for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>(i % 7);
  Session session;
  SessionTypeA type_a;
  for (int sensor : {2, 5}) {
    Tag tag = MakeTag(v);
    tag.sensor = sensor;
    tag.quantities.clear();
    TagTypeA t;
    t.sensor = sensor;
    t.window = Window(0, v.size());
    for (const char* name : {"qw", "pitch_deg", "gx_dps"}) {
      tag.quantities.push_back({name, "1", QuantityOrigin::kFile, v});
      QuantityTypeA q = Evaluated(v, 0, v.size());
      q.name = name;
      t.quantities.push_back(q);
    }
    session.tags.push_back(tag);
    type_a.tags.push_back(t);
  }
  PlotDataOptions options;
  options.max_quantities = 3;
  Result<SessionPlotData> data = ComputeSessionPlotData(session, type_a, options);
  REQUIRE(data.ok());
  const auto& q = data.value().quantities;
  REQUIRE(q.size() == 2);
  CHECK_FALSE(q[0][0].has_value());
  CHECK(q[0][1].has_value());
  CHECK(q[0][2].has_value());
  CHECK_FALSE(q[1][0].has_value());
  CHECK(q[1][1].has_value());
  CHECK_FALSE(q[1][2].has_value());
  CHECK(data.value().not_plotted == 1);

  // Named quantities: only those, the quaternion's too.
  options.quantities = {"qw"};
  data = ComputeSessionPlotData(session, type_a, options);
  REQUIRE(data.ok());
  CHECK(data.value().quantities[0][0].has_value());
  CHECK_FALSE(data.value().quantities[0][1].has_value());
  CHECK(data.value().not_plotted == 0);

  // A column the evaluation names but the session lacks is an error, not a skipped plot.
  session.tags[0].quantities.pop_back();
  options.quantities.clear();
  CHECK_FALSE(ComputeSessionPlotData(session, type_a, options).ok());
}

}  // namespace
}  // namespace metro
