#include "plot_data_json.hpp"

#include <fmt/format.h>

namespace metro {

using ordered_json = nlohmann::ordered_json;

ordered_json PlotDataToJsonValue(const QuantityPlotData& data) {
  const SeriesPlotData& s = data.series;
  ordered_json plot;
  plot["series"] = {
      {"n_record", s.n_record},
      {"n_window", s.n_window},
      {"record_first_t_s", s.record_first_t_s},
      {"record_last_t_s", s.record_last_t_s},
      {"window_first_t_s", s.window_first_t_s},
      {"window_end_t_s", s.window_end_t_s ? ordered_json(*s.window_end_t_s) : ordered_json()},
      {"t_s", s.t_s},
      {"values", s.values}};
  if (data.histogram) {
    const HistogramPlotData& h = *data.histogram;
    plot["histogram"] = {{"n", h.n},
                         {"resolution", h.resolution},
                         {"density_mean", h.density_mean},
                         {"edges", h.edges_value},
                         {"counts", h.counts}};
  } else {
    plot["histogram"] = nullptr;
  }
  if (data.autocorrelation) {
    const AutocorrelationPlotData& a = *data.autocorrelation;
    plot["autocorrelation"] = {{"n", a.n}, {"band", a.band}, {"rho", a.rho}};
  } else {
    plot["autocorrelation"] = nullptr;
  }
  return plot;
}

QuantityPlotData PlotDataFromJsonValue(const JsonCursor& plot) {
  QuantityPlotData data;
  const JsonCursor s = plot["series"];
  SeriesPlotData& series = data.series;
  series.n_record = s["n_record"].Integer();
  series.n_window = s["n_window"].Integer();
  series.record_first_t_s = s["record_first_t_s"].Number();
  series.record_last_t_s = s["record_last_t_s"].Number();
  series.window_first_t_s = s["window_first_t_s"].Number();
  series.window_end_t_s = s["window_end_t_s"].OptionalNumber();
  if (!s["window_end_t_s"].Present()) s["window_end_t_s"].Fail("a number or null");
  series.t_s = s["t_s"].Numbers();
  series.values = s["values"].Numbers();
  if (series.t_s.size() != series.values.size()) {
    s["values"].Fail(fmt::format("as many values as t_s ({})", series.t_s.size()));
  }
  if (!plot["histogram"].IsNull()) {
    const JsonCursor h = plot["histogram"];
    HistogramPlotData hist;
    hist.n = h["n"].Integer();
    hist.resolution = h["resolution"].Number();
    hist.density_mean = h["density_mean"].Number();
    hist.edges_value = h["edges"].Numbers();
    hist.counts = h["counts"].Integers();
    if (hist.edges_value.size() != hist.counts.size() + 1) {
      h["edges"].Fail(fmt::format("one edge more than counts ({} edges)", hist.counts.size() + 1));
    }
    data.histogram = std::move(hist);
  }
  if (!plot["autocorrelation"].IsNull()) {
    const JsonCursor a = plot["autocorrelation"];
    AutocorrelationPlotData ac;
    ac.n = a["n"].Integer();
    ac.band = a["band"].Number();
    ac.rho = a["rho"].Numbers();
    data.autocorrelation = std::move(ac);
  }
  return data;
}

}  // namespace metro
