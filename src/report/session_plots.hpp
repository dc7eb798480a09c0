// The figures of the session page ("metro.report/1", docs/reports.md): per quantity the time
// series, histogram, autocorrelation and Allan deviation, per sensor group the x/y/z Allan
// plot. html_report.cpp puts them together with the tables (session_tables.hpp). Private to
// src/report/.
#pragma once

#include <kainjow/mustache.hpp>
#include <string>

#include "metro/report/plot_data.hpp"
#include "metro/report/session_report.hpp"

namespace metro::report_internal {

// A list of figures {svg, caption} and notes on the plots that could not be drawn.
struct QuantityPlots {
  kainjow::mustache::data plots{kainjow::mustache::data::type::list};
  kainjow::mustache::data unavailable{kainjow::mustache::data::type::list};
};

// Time series (the part outside the window shaded), histogram with the normal density of
// the Type A result, and autocorrelation with the white-noise band of `quantity`, drawn from
// its plot data (computed when the session was analysed, plot_data.hpp). Each axis carries
// its scale and offset in the label (ChooseAxisScale), never a detached "x10^n".
void AddSeriesPlots(const QuantityReport& quantity, const QuantityPlotData& data,
                    QuantityPlots* out);

// The Allan deviation of one quantity with its confidence interval and the fitted IEEE 952
// terms; `terms_table` receives the table of the terms.
void AddAllanPlot(const QuantityReport& quantity, QuantityPlots* out,
                  kainjow::mustache::data* terms_table);

// One plot per sensor group of `sensor` (the x, y and z axes of one sensor: ax_g ay_g az_g,
// gx_dps gy_dps gz_dps; names <letters><x|y|z>_<unit>, one unit) with two or more Allan
// curves: each axis's curve with its confidence interval and its fitted noise model, one
// colour per axis (x blue, y orange, z green).
void AddAllanGroupPlots(const SensorReport& sensor, QuantityPlots* out);

}  // namespace metro::report_internal
