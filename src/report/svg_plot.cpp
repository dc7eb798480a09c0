#include "metro/report/svg_plot.hpp"

#include <fmt/format.h>
#include <plplot/plplot.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <mutex>

#include "metro/core/file.hpp"

namespace metro {
namespace {

// PLplot is not thread-safe: one plot at a time in the process.
std::mutex& PlplotMutex() {
  static std::mutex mutex;
  return mutex;
}

// Colour map 0: 0 background, 1 axes and text, then the palette in PlotColor order, then
// the band shade, the decade grid and the minor grid of log axes.
constexpr PLINT kCmapSize = 12;
constexpr PLINT kRed[kCmapSize] = {255, 0, 31, 255, 44, 214, 148, 127, 0, 225, 176, 226};
constexpr PLINT kGreen[kCmapSize] = {255, 0, 119, 127, 160, 39, 103, 127, 0, 225, 184, 230};
constexpr PLINT kBlue[kCmapSize] = {255, 0, 180, 14, 44, 40, 189, 127, 0, 225, 194, 236};
constexpr PLINT kAxisColor = 1;
constexpr PLINT kBandColor = 9;
constexpr PLINT kDecadeGridColor = 10;
constexpr PLINT kMinorGridColor = 11;

PLINT ColorIndex(PlotColor c) { return 2 + static_cast<PLINT>(c); }

// PLplot treats '#' as its escape character.
std::string PlText(const std::string& s) {
  std::string out;
  for (char c : s) {
    out += c;
    if (c == '#') out += '#';
  }
  return out;
}

// $TMPDIR, or /tmp when it is unset or empty.
std::string TempDirectory() {
  const char* dir = std::getenv("TMPDIR");
  return dir != nullptr && *dir != '\0' ? dir : "/tmp";
}

// A PLplot stream writing SVG to a temporary file; the text is read back by Finish().
class SvgStream {
 public:
  SvgStream(int width_px, int height_px) {
    std::string name = TempDirectory() + "/metro_plot_XXXXXX";
    const int fd = ::mkstemp(name.data());
    if (fd < 0) return;
    ::close(fd);
    path_ = name;
    cleanup_.Reset(path_);  // Removed by SIGINT/SIGTERM too (InstallInterruptCleanup).
    plgstrm(&previous_);
    plmkstrm(&stream_);
    plsdev("svg");
    plsfnam(path_.c_str());
    const std::string geometry = fmt::format("{}x{}", width_px, height_px);
    plsetopt("geometry", geometry.c_str());
    plscmap0(kRed, kGreen, kBlue, kCmapSize);
    plinit();
    plschr(0.0, 0.8);
    plssym(0.0, 0.7);
    open_ = true;
  }
  SvgStream(const SvgStream&) = delete;
  SvgStream& operator=(const SvgStream&) = delete;
  ~SvgStream() {
    if (open_) plend1();
    if (!path_.empty()) std::remove(path_.c_str());
  }
  bool ok() const { return open_; }

  Result<std::string> Finish() {
    plend1();
    open_ = false;
    plsstrm(previous_);
    Result<std::string> text = ReadFile(path_);
    if (!text.ok()) return text.error();
    return InlineSvg(text.value());
  }

 private:
  // Drops everything before "<svg", the namespace declarations (inline SVG in HTML needs
  // none) and the fixed width/height, so the plot scales with the page.
  static Result<std::string> InlineSvg(const std::string& svg) {
    const size_t begin = svg.find("<svg");
    if (begin == std::string::npos) return MakeError("PLplot wrote no <svg> element");
    std::string out = svg.substr(begin);
    for (const char* attr :
         {"xmlns=\"http://www.w3.org/2000/svg\"", "xmlns:xlink=\"http://www.w3.org/1999/xlink\""}) {
      const size_t at = out.find(attr);
      if (at != std::string::npos) out.erase(at, std::char_traits<char>::length(attr));
    }
    for (const char* attr : {"width=\"", "height=\""}) {
      // Only the first occurrence: the <svg> element's own size.
      const size_t at = out.find(attr);
      const size_t end = at == std::string::npos ? at : out.find('"', at + std::strlen(attr));
      if (end != std::string::npos) out.erase(at, end + 1 - at);
    }
    out.insert(4, " class=\"plot\" role=\"img\"");
    return out;
  }

  std::string path_;
  RemoveOnInterrupt cleanup_;  // path_ while it exists.
  PLINT previous_ = 0;
  PLINT stream_ = -1;
  bool open_ = false;
};

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool empty() const { return !(lo <= hi); }
  // Adds a margin; a degenerate range is widened.
  void Pad(bool log) {
    if (empty()) {
      lo = log ? -1.0 : 0.0;
      hi = log ? 1.0 : 1.0;
      return;
    }
    double span = hi - lo;
    if (span <= 0.0) span = log ? 1.0 : std::max(std::abs(lo) * 1e-3, 1e-12);
    lo -= 0.05 * span;
    hi += 0.05 * span;
  }
};

// log10 for a log axis, the value otherwise; non-positive values on a log axis are NaN.
double Axis(double v, bool log) {
  if (!log) return v;
  return v > 0.0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<PLFLT> AxisValues(const std::vector<double>& v, bool log) {
  std::vector<PLFLT> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = Axis(v[i], log);
  return out;
}

// Calls `draw(first, count)` for each run of points where both coordinates are finite.
template <typename F>
void ForFiniteRuns(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, F draw) {
  size_t i = 0;
  const size_t n = std::min(x.size(), y.size());
  while (i < n) {
    while (i < n && !(std::isfinite(x[i]) && std::isfinite(y[i]))) ++i;
    size_t j = i;
    while (j < n && std::isfinite(x[j]) && std::isfinite(y[j])) ++j;
    if (j > i) draw(i, j - i);
    i = j;
  }
}

void DrawSeries(const PlotSeries& s, bool log_x, bool log_y, double y_floor) {
  const std::vector<PLFLT> x = AxisValues(s.x, log_x);
  const std::vector<PLFLT> y = AxisValues(s.y, log_y);
  plcol0(ColorIndex(s.color));
  switch (s.style) {
    case SeriesStyle::kLine:
      pllsty(s.dashed ? 2 : 1);
      plwidth(1.5);
      ForFiniteRuns(x, y, [&](size_t i, size_t n) { plline(static_cast<PLINT>(n), &x[i], &y[i]); });
      pllsty(1);
      plwidth(1.0);
      break;
    case SeriesStyle::kPoints:
      ForFiniteRuns(x, y,
                    [&](size_t i, size_t n) { plpoin(static_cast<PLINT>(n), &x[i], &y[i], 17); });
      break;
    case SeriesStyle::kStems:
      for (size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
        if (!std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
        pljoin(x[i], y_floor, x[i], y[i]);
      }
      break;
    case SeriesStyle::kErrorBars: {
      const std::vector<PLFLT> lo = AxisValues(s.y_low, log_y);
      const std::vector<PLFLT> hi = AxisValues(s.y_high, log_y);
      for (size_t i = 0; i < std::min({x.size(), y.size(), lo.size(), hi.size()}); ++i) {
        if (!std::isfinite(x[i]) || !std::isfinite(lo[i]) || !std::isfinite(hi[i])) continue;
        PLFLT xi = x[i], l = lo[i], h = hi[i];
        plerry(1, &xi, &l, &h);
      }
      ForFiniteRuns(x, y,
                    [&](size_t i, size_t n) { plpoin(static_cast<PLINT>(n), &x[i], &y[i], 17); });
      break;
    }
    case SeriesStyle::kBins:
      for (size_t i = 0; i + 1 < x.size() && i < y.size(); ++i) {
        if (!std::isfinite(x[i]) || !std::isfinite(x[i + 1]) || !std::isfinite(y[i])) continue;
        PLFLT bx[4] = {x[i], x[i], x[i + 1], x[i + 1]};
        PLFLT by[4] = {y_floor, y[i], y[i], y_floor};
        plcol0(ColorIndex(s.color));
        plfill(4, bx, by);
        plcol0(0);
        plline(4, bx, by);
      }
      break;
  }
}

void DrawLegend(const XyPlot& plot) {
  std::vector<PLINT> opt, text_colors, line_colors, line_styles, symbol_colors, symbol_numbers,
      box_colors, box_patterns;
  std::vector<PLFLT> line_widths, symbol_scales, box_scales, box_line_widths;
  std::vector<std::string> texts;
  std::vector<std::string> symbols;
  auto add = [&](const std::string& label, PLINT kind, PLINT color, bool dashed) {
    opt.push_back(kind);
    text_colors.push_back(kAxisColor);
    texts.push_back(PlText(label));
    line_colors.push_back(color);
    line_styles.push_back(dashed ? 2 : 1);
    line_widths.push_back(1.5);
    symbol_colors.push_back(color);
    symbol_scales.push_back(1.0);
    symbol_numbers.push_back(1);
    symbols.push_back("#(728)");  // Hershey filled circle.
    box_colors.push_back(color);
    box_patterns.push_back(0);
    box_scales.push_back(0.8);
    box_line_widths.push_back(1.0);
  };
  for (const PlotBand& b : plot.bands) {
    if (!b.label.empty()) add(b.label, PL_LEGEND_COLOR_BOX, kBandColor, false);
  }
  for (const PlotHLine& h : plot.hlines) {
    if (!h.label.empty()) add(h.label, PL_LEGEND_LINE, ColorIndex(h.color), h.dashed);
  }
  for (const PlotSeries& s : plot.series) {
    if (s.label.empty()) continue;
    const PLINT kind = s.style == SeriesStyle::kLine   ? PL_LEGEND_LINE
                       : s.style == SeriesStyle::kBins ? PL_LEGEND_COLOR_BOX
                                                       : PL_LEGEND_SYMBOL;
    add(s.label, kind, ColorIndex(s.color), s.dashed);
  }
  if (texts.empty()) return;
  std::vector<const char*> text_ptrs, symbol_ptrs;
  for (const std::string& t : texts) text_ptrs.push_back(t.c_str());
  for (const std::string& t : symbols) symbol_ptrs.push_back(t.c_str());
  PLFLT width = 0.0, height = 0.0;
  pllegend(&width, &height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_RIGHT | PL_POSITION_TOP | PL_POSITION_INSIDE, 0.01, 0.01, 0.05, 0,
           kAxisColor, 1, 0, 0, static_cast<PLINT>(texts.size()), opt.data(), 1.0, 0.8, 1.6, 0.0,
           text_colors.data(), text_ptrs.data(), box_colors.data(), box_patterns.data(),
           box_scales.data(), box_line_widths.data(), line_colors.data(), line_styles.data(),
           line_widths.data(), symbol_colors.data(), symbol_scales.data(), symbol_numbers.data(),
           symbol_ptrs.data());
}

// The grid of the log axes (log_x: vertical lines, log_y: horizontal ones) inside the
// window [x_lo, x_hi] x [y_lo, y_hi] (log10 units on a log axis): light lines at 2..9 x 10^n
// first, then a darker line at every power of ten, so a reader can tell a decade apart and
// read a slope of -1/2 (white noise) or +1/2 (rate random walk) off the curve.
void DrawLogGrid(bool log_x, bool log_y, double x_lo, double x_hi, double y_lo, double y_hi) {
  auto lines = [](double lo, double hi, bool minor, auto draw) {
    for (double n = std::floor(lo); n <= std::ceil(hi); n += 1.0) {
      for (int m = minor ? 2 : 1; m <= (minor ? 9 : 1); ++m) {
        const double at = n + std::log10(static_cast<double>(m));
        if (at >= lo && at <= hi) draw(at);
      }
    }
  };
  plwidth(0.5);
  for (const bool minor : {true, false}) {
    plcol0(minor ? kMinorGridColor : kDecadeGridColor);
    if (log_x) lines(x_lo, x_hi, minor, [&](double x) { pljoin(x, y_lo, x, y_hi); });
    if (log_y) lines(y_lo, y_hi, minor, [&](double y) { pljoin(x_lo, y, x_hi, y); });
  }
  plwidth(1.0);
}

bool CheckSize(int width_px, int height_px, std::string* why) {
  if (width_px < 100 || width_px > 4000 || height_px < 100 || height_px > 4000) {
    *why = fmt::format("plot size {}x{} px is outside 100..4000 px", width_px, height_px);
    return false;
  }
  return true;
}

}  // namespace

bool XyPlot::IsValid(std::string* why) const {
  if (!CheckSize(width_px, height_px, why)) return false;
  for (const PlotSeries& s : series) {
    const size_t want_x = s.style == SeriesStyle::kBins ? s.y.size() + 1 : s.y.size();
    if (s.x.size() != want_x) {
      *why = fmt::format("plot '{}': series '{}' has {} x values for {} y values", title, s.label,
                         s.x.size(), s.y.size());
      return false;
    }
    if (s.style == SeriesStyle::kErrorBars &&
        (s.y_low.size() != s.y.size() || s.y_high.size() != s.y.size())) {
      *why = fmt::format("plot '{}': error bars of series '{}' do not match its {} points", title,
                         s.label, s.y.size());
      return false;
    }
  }
  return true;
}

bool BarPlot::IsValid(std::string* why) const {
  if (labels.size() != values.size()) {
    *why =
        fmt::format("bar plot '{}': {} labels for {} values", title, labels.size(), values.size());
    return false;
  }
  if (labels.empty()) {
    *why = fmt::format("bar plot '{}' has no bars", title);
    return false;
  }
  for (double v : values) {
    if (!std::isfinite(v) || v < 0.0) {
      *why = fmt::format("bar plot '{}': bar value {} is not a finite number >= 0", title, v);
      return false;
    }
  }
  return CheckSize(width_px, height_px == 0 ? 100 : height_px, why);
}

Result<std::string> RenderXyPlot(const XyPlot& plot) {
  std::string why;
  if (!plot.IsValid(&why)) return MakeError(why);
  Range xr, yr;
  for (const PlotSeries& s : plot.series) {
    for (double v : s.x) xr.Add(Axis(v, plot.log_x));
    for (double v : s.y) yr.Add(Axis(v, plot.log_y));
    for (double v : s.y_low) yr.Add(Axis(v, plot.log_y));
    for (double v : s.y_high) yr.Add(Axis(v, plot.log_y));
    if ((s.style == SeriesStyle::kBins || s.style == SeriesStyle::kStems) && !plot.log_y) {
      yr.Add(0.0);
    }
  }
  for (const PlotHLine& h : plot.hlines) yr.Add(Axis(h.y, plot.log_y));
  for (const PlotBand& b : plot.bands) {
    xr.Add(Axis(b.x_min, plot.log_x));
    xr.Add(Axis(b.x_max, plot.log_x));
  }
  xr.Pad(plot.log_x);
  yr.Pad(plot.log_y);
  // Room for the legend above the data.
  const size_t legend_rows = std::count_if(plot.series.begin(), plot.series.end(),
                                           [](const PlotSeries& s) { return !s.label.empty(); }) +
                             std::count_if(plot.bands.begin(), plot.bands.end(),
                                           [](const PlotBand& b) { return !b.label.empty(); }) +
                             std::count_if(plot.hlines.begin(), plot.hlines.end(),
                                           [](const PlotHLine& h) { return !h.label.empty(); });
  yr.hi += (yr.hi - yr.lo) * 0.07 * static_cast<double>(legend_rows);

  std::lock_guard<std::mutex> lock(PlplotMutex());
  SvgStream stream(plot.width_px, plot.height_px);
  if (!stream.ok())
    return MakeError("cannot create a temporary file for a plot in " + TempDirectory() +
                     " (set TMPDIR to a writable directory)");
  pladv(0);
  plvpor(0.1, 0.96, 0.14, 0.9);
  plwind(xr.lo, xr.hi, yr.lo, yr.hi);
  const double y_floor = plot.log_y ? yr.lo : 0.0;
  for (const PlotBand& b : plot.bands) {
    PLFLT bx0 = std::max(Axis(b.x_min, plot.log_x), xr.lo);
    PLFLT bx1 = std::min(Axis(b.x_max, plot.log_x), xr.hi);
    if (!(bx1 > bx0)) continue;
    PLFLT bx[4] = {bx0, bx0, bx1, bx1};
    PLFLT by[4] = {yr.lo, yr.hi, yr.hi, yr.lo};
    plcol0(kBandColor);
    plfill(4, bx, by);
  }
  DrawLogGrid(plot.log_x, plot.log_y, xr.lo, xr.hi, yr.lo, yr.hi);
  plcol0(kAxisColor);
  const std::string xopt = plot.log_x ? "bcnstl" : "bcnst";
  const std::string yopt = plot.log_y ? "bcnstvl" : "bcnstv";
  plbox(xopt.c_str(), 0.0, 0, yopt.c_str(), 0.0, 0);
  for (const PlotHLine& h : plot.hlines) {
    const double y = Axis(h.y, plot.log_y);
    if (!std::isfinite(y)) continue;
    plcol0(ColorIndex(h.color));
    pllsty(h.dashed ? 2 : 1);
    pljoin(xr.lo, y, xr.hi, y);
    pllsty(1);
  }
  for (const PlotSeries& s : plot.series) DrawSeries(s, plot.log_x, plot.log_y, y_floor);
  plcol0(kAxisColor);
  pllab(PlText(plot.x_label).c_str(), PlText(plot.y_label).c_str(), PlText(plot.title).c_str());
  DrawLegend(plot);
  return stream.Finish();
}

Result<std::string> RenderBarPlot(const BarPlot& plot) {
  std::string why;
  if (!plot.IsValid(&why)) return MakeError(why);
  const size_t n = plot.values.size();
  const int height_px = plot.height_px > 0 ? plot.height_px : 60 + 28 * static_cast<int>(n);
  size_t longest = 0;
  for (const std::string& l : plot.labels) longest = std::max(longest, l.size());
  const double left = std::clamp(0.02 + 0.0095 * static_cast<double>(longest), 0.1, 0.5);
  const double x_max = *std::max_element(plot.values.begin(), plot.values.end());
  const double x_hi = x_max > 0.0 ? x_max * 1.18 : 1.0;

  std::lock_guard<std::mutex> lock(PlplotMutex());
  SvgStream stream(plot.width_px, std::min(height_px, 4000));
  if (!stream.ok())
    return MakeError("cannot create a temporary file for a plot in " + TempDirectory() +
                     " (set TMPDIR to a writable directory)");
  pladv(0);
  const double bottom = std::min(0.5, 45.0 / height_px);
  const double top = 1.0 - std::min(0.3, 30.0 / height_px);
  plvpor(left, 0.96, bottom, top);
  const double n_d = static_cast<double>(n);
  plwind(0.0, x_hi, 0.0, n_d);
  plcol0(kAxisColor);
  plbox("bcnst", 0.0, 0, "bc", 0.0, 0);
  for (size_t i = 0; i < n; ++i) {
    // Bar i from the top.
    const double y0 = n_d - static_cast<double>(i) - 0.8;
    const double y1 = n_d - static_cast<double>(i) - 0.2;
    PLFLT bx[4] = {0.0, 0.0, plot.values[i], plot.values[i]};
    PLFLT by[4] = {y0, y1, y1, y0};
    plcol0(ColorIndex(PlotColor::kBlue));
    plfill(4, bx, by);
    plcol0(kAxisColor);
    plmtex("lv", 0.5, (n_d - static_cast<double>(i) - 0.5) / n_d, 1.0,
           PlText(plot.labels[i]).c_str());
    const std::string value = fmt::format("{:.3g}", plot.values[i]);
    plptex(plot.values[i] + x_hi * 0.01, 0.5 * (y0 + y1) - 0.1, 1.0, 0.0, 0.0, value.c_str());
  }
  pllab(PlText(plot.x_label).c_str(), "", PlText(plot.title).c_str());
  return stream.Finish();
}

}  // namespace metro
