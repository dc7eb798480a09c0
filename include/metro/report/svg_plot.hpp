// Report plots: PLplot's "svg" device draws each plot; the SVG is returned as text ready to
// be inlined in an HTML page (no XML prolog, no DOCTYPE, no namespace URLs, so the page
// makes no network reference).
//
// PLplot keeps global state and is not thread-safe; every call here holds one process-wide
// lock, so plots may be requested from any thread (they are drawn one at a time).
#pragma once

#include <string>
#include <vector>

#include "metro/core/status.hpp"

namespace metro {

// Colours of the report palette (index into the PLplot colour map 0 set up by the plots).
enum class PlotColor { kBlue, kOrange, kGreen, kRed, kPurple, kGrey, kBlack };

enum class SeriesStyle {
  kLine,       // Polyline through (x, y).
  kPoints,     // A marker at each (x, y).
  kStems,      // A vertical line from y = 0 to each y.
  kErrorBars,  // A marker at each (x, y) with a vertical bar from y_low to y_high.
  kBins,       // Histogram: bars between consecutive x (x has one more element than y).
};

struct PlotSeries {
  std::string label;  // Legend text; empty: not in the legend.
  SeriesStyle style = SeriesStyle::kLine;
  PlotColor color = PlotColor::kBlue;
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> y_low;   // kErrorBars only, same size as y.
  std::vector<double> y_high;  // kErrorBars only, same size as y.
  bool dashed = false;         // kLine only.
};

// A shaded vertical band x_min <= x <= x_max over the whole height (e.g. the settle
// window excluded from the evaluation).
struct PlotBand {
  std::string label;
  double x_min = 0.0;
  double x_max = 0.0;
};

// A horizontal reference line (e.g. the mean, a confidence band).
struct PlotHLine {
  std::string label;
  double y = 0.0;
  PlotColor color = PlotColor::kGrey;
  bool dashed = true;
};

struct XyPlot {
  std::string title;
  std::string x_label;
  std::string y_label;
  // Logarithmic axes: every plotted value must then be > 0. A log axis gets a grid: a line
  // at every power of ten (10^n) and lighter lines at 2..9 x 10^n, across the plot.
  bool log_x = false;
  bool log_y = false;
  int width_px = 800;
  int height_px = 340;
  std::vector<PlotBand> bands;
  std::vector<PlotHLine> hlines;
  std::vector<PlotSeries> series;

  bool IsValid(std::string* why) const;
};

// Horizontal bars, drawn in the order given from the top (sort before calling).
struct BarPlot {
  std::string title;
  std::string x_label;
  std::vector<std::string> labels;
  std::vector<double> values;  // >= 0 and finite.
  int width_px = 800;
  int height_px = 0;  // 0: 60 + 28 per bar.

  bool IsValid(std::string* why) const;
};

// The SVG text of the plot ("<svg ...>...</svg>", scaled to the page width by CSS).
// Non-finite points are skipped. Errors: an invalid plot, PLplot failing to write.
Result<std::string> RenderXyPlot(const XyPlot& plot);
Result<std::string> RenderBarPlot(const BarPlot& plot);

}  // namespace metro
