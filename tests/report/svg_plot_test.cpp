// PLplot SVG plots: inline-ready SVG, deterministic, drawn elements, bad input.
#include "metro/report/svg_plot.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace metro {
namespace {

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

XyPlot LinePlot() {
  XyPlot p;
  p.title = "line";
  p.x_label = "t_s [s]";
  p.y_label = "y [1]";
  PlotSeries s;
  for (int i = 0; i < 50; ++i) {
    s.x.push_back(i * 0.1);
    s.y.push_back(std::sin(i * 0.1));
  }
  p.series.push_back(s);
  p.bands.push_back({"settle", 0.0, 1.0});
  return p;
}

TEST_CASE("XY plot is inline SVG without prolog or network references", "[report][plot]") {
  Result<std::string> svg = RenderXyPlot(LinePlot());
  REQUIRE(svg.ok());
  const std::string& s = svg.value();
  CHECK(s.rfind("<svg", 0) == 0);
  CHECK(s.find("</svg>") != std::string::npos);
  CHECK(s.find("<?xml") == std::string::npos);
  CHECK(s.find("DOCTYPE") == std::string::npos);
  CHECK(s.find("http") == std::string::npos);
  CHECK(s.find("class=\"plot\"") != std::string::npos);
  CHECK(s.find("polyline") != std::string::npos);
  // Deterministic: the same plot twice is the same text.
  Result<std::string> again = RenderXyPlot(LinePlot());
  REQUIRE(again.ok());
  CHECK(again.value() == s);
}

TEST_CASE("Bar plot draws one filled shape per bar", "[report][plot]") {
  BarPlot one, few, more;
  one.title = few.title = more.title = "budget";
  one.labels = {"a"};
  one.values = {100.0};
  few.labels = {"a", "b"};
  few.values = {70.0, 30.0};
  more.labels = {"a", "b", "c", "d", "e"};
  more.values = {50.0, 20.0, 15.0, 10.0, 5.0};
  Result<std::string> s1 = RenderBarPlot(one);
  Result<std::string> s2 = RenderBarPlot(few);
  REQUIRE(s1.ok());
  Result<std::string> s5 = RenderBarPlot(more);
  REQUIRE(s2.ok());
  REQUIRE(s5.ok());
  // The frame is the same in all: each bar adds the same number of polygons.
  const size_t per_bar = Count(s2.value(), "<polygon") - Count(s1.value(), "<polygon");
  CHECK(per_bar >= 1);
  CHECK(Count(s5.value(), "<polygon") - Count(s2.value(), "<polygon") == 3 * per_bar);
}

TEST_CASE("Log-log plot with error bars renders", "[report][plot]") {
  XyPlot p;
  p.log_x = p.log_y = true;
  PlotSeries s;
  s.style = SeriesStyle::kErrorBars;
  for (int i = 0; i < 8; ++i) {
    const double tau = std::pow(2.0, i);
    s.x.push_back(tau);
    s.y.push_back(1.0 / std::sqrt(tau));
    s.y_low.push_back(0.8 / std::sqrt(tau));
    s.y_high.push_back(1.2 / std::sqrt(tau));
  }
  p.series.push_back(s);
  Result<std::string> svg = RenderXyPlot(p);
  REQUIRE(svg.ok());
  CHECK(svg.value().find("polyline") != std::string::npos);
}

// The polylines of an SVG drawn in `stroke` ("#RRGGBB"), each as its points (x, y) in the
// SVG's pixel coordinates.
std::vector<std::vector<std::pair<double, double>>> Polylines(const std::string& svg,
                                                              const std::string& stroke) {
  std::vector<std::vector<std::pair<double, double>>> out;
  for (size_t at = svg.find("<polyline"); at != std::string::npos;
       at = svg.find("<polyline", at + 1)) {
    const std::string element = svg.substr(at, svg.find("/>", at) - at);
    if (element.find("stroke=\"" + stroke + "\"") == std::string::npos) continue;
    const size_t p = element.find("points=\"") + 8;
    std::istringstream points(element.substr(p, element.find('"', p) - p));
    std::vector<std::pair<double, double>> line;
    double x = 0.0, y = 0.0;
    char comma = 0;
    while (points >> x >> comma >> y) line.emplace_back(x, y);
    out.push_back(line);
  }
  return out;
}

TEST_CASE("Log axes get a line at each decade and lighter ones at 2..9 x 10^n", "[report][plot]") {
  // A line from (0.01, 1e-2) to (10, 1e-4): its ends are at known decades, so the pixel
  // position of every decade follows from them (a log axis is linear in log10).
  XyPlot p;
  p.log_x = p.log_y = true;
  PlotSeries s;
  s.x = {0.01, 10.0};
  s.y = {1e-2, 1e-4};
  p.series.push_back(s);
  Result<std::string> svg = RenderXyPlot(p);
  REQUIRE(svg.ok());
  const auto curve = Polylines(svg.value(), "#1F77B4");  // PlotColor::kBlue.
  REQUIRE(curve.size() == 1);
  REQUIRE(curve[0].size() == 2);
  const double x0 = curve[0][0].first, x_decade = (curve[0][1].first - x0) / 3.0;
  const double y0 = curve[0][0].second, y_decade = (y0 - curve[0][1].second) / 2.0;
  REQUIRE(x_decade > 50.0);
  REQUIRE(y_decade > 30.0);
  // The SVG writes coordinates to 0.01 px: a line is where it belongs to within 0.05 px
  // (a decade is more than 30 px, so a misplaced line is off by pixels).
  constexpr double kPx = 0.05;
  // Where a grid line is in decades from the curve's start (x: from tau = 0.01 up, y: from
  // 1e-2 down), and whether the line is vertical.
  auto positions = [&](const std::string& stroke, std::vector<double>* vertical,
                       std::vector<double>* horizontal) {
    for (const auto& line : Polylines(svg.value(), stroke)) {
      REQUIRE(line.size() == 2);
      if (std::fabs(line[0].first - line[1].first) < 0.01) {
        vertical->push_back((line[0].first - x0) / x_decade);
      } else {
        REQUIRE(std::fabs(line[0].second - line[1].second) < 0.01);
        horizontal->push_back((y0 - line[0].second) / y_decade);
      }
    }
  };
  std::vector<double> major_x, major_y, minor_x, minor_y;
  positions("#B0B8C2", &major_x, &major_y);
  positions("#E2E6EC", &minor_x, &minor_y);
  // Every decade the data span has its line: 0.01, 0.1, 1, 10 s and 1e-2, 1e-3, 1e-4; each
  // line is at a whole decade.
  for (double d : {0.0, 1.0, 2.0, 3.0}) {
    CHECK(std::count_if(major_x.begin(), major_x.end(), [d, x_decade](double v) {
            return std::fabs(v - d) * x_decade < kPx;
          }) == 1);
  }
  for (double d : {0.0, 1.0, 2.0}) {
    CHECK(std::count_if(major_y.begin(), major_y.end(), [d, y_decade](double v) {
            return std::fabs(v - d) * y_decade < kPx;
          }) == 1);
  }
  for (double v : major_x) CHECK(std::fabs(v - std::round(v)) * x_decade < kPx);
  for (double v : major_y) CHECK(std::fabs(v - std::round(v)) * y_decade < kPx);
  // 2..9 x 10^n between them: 8 per decade, log10(m) of a decade past the decade's line (y
  // runs downwards in decades, so 2 x 10^-3 is 1 - log10(2) decades below 1e-2).
  CHECK(minor_x.size() >= 3 * 8);
  CHECK(minor_y.size() >= 2 * 8);
  for (int n = 0; n < 3; ++n) {
    for (int m = 2; m <= 9; ++m) {
      const double want_x = n + std::log10(m);
      const double want_y = n + 1 - std::log10(m);
      CHECK(std::count_if(minor_x.begin(), minor_x.end(),
                          [&](double v) { return std::fabs(v - want_x) * x_decade < kPx; }) == 1);
      if (n < 2) {
        CHECK(std::count_if(minor_y.begin(), minor_y.end(),
                            [&](double v) { return std::fabs(v - want_y) * y_decade < kPx; }) == 1);
      }
    }
  }
  // A linear plot has no grid.
  Result<std::string> linear = RenderXyPlot(LinePlot());
  REQUIRE(linear.ok());
  CHECK(Polylines(linear.value(), "#B0B8C2").empty());
  CHECK(Polylines(linear.value(), "#E2E6EC").empty());
}

TEST_CASE("Bad plots are refused with a message", "[report][plot]") {
  XyPlot p = LinePlot();
  p.series[0].x.pop_back();
  Result<std::string> r = RenderXyPlot(p);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "plot 'line': series '' has 49 x values for 50 y values");

  p = LinePlot();
  p.series[0].style = SeriesStyle::kErrorBars;
  r = RenderXyPlot(p);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "plot 'line': error bars of series '' do not match its 50 points");

  p = LinePlot();
  p.width_px = 10;
  r = RenderXyPlot(p);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "plot size 10x340 px is outside 100..4000 px");

  BarPlot b;
  b.title = "u";
  b.labels = {"a"};
  b.values = {-1.0};
  r = RenderBarPlot(b);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "bar plot 'u': bar value -1 is not a finite number >= 0");
  b.values = {};
  r = RenderBarPlot(b);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "bar plot 'u': 1 labels for 0 values");
  b.labels = {};
  r = RenderBarPlot(b);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message == "bar plot 'u' has no bars");
}

}  // namespace
}  // namespace metro
