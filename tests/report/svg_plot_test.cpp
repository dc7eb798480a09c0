// PLplot SVG plots: inline-ready SVG, deterministic, drawn elements, bad input.
#include "metro/report/svg_plot.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

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
