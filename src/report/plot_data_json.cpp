#include "plot_data_json.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>

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
  if (series.n_record < 1) s["n_record"].Fail("a number of observations >= 1");
  if (series.n_window < 0 || series.n_window > series.n_record) {
    s["n_window"].Fail(fmt::format("0..n_record ({})", series.n_record));
  }
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
    for (size_t i = 1; i < hist.edges_value.size(); ++i) {
      if (!(hist.edges_value[i] > hist.edges_value[i - 1])) {
        h["edges"][i].Fail("edges in increasing order");
        break;
      }
    }
    int64_t total = 0;
    for (size_t i = 0; i < hist.counts.size(); ++i) {
      if (hist.counts[i] < 0) h["counts"][i].Fail("a count >= 0");
      total += std::max<int64_t>(0, std::min<int64_t>(hist.counts[i], int64_t{1} << 53));
    }
    if (hist.n < 1 || total != hist.n) {
      h["n"].Fail(fmt::format("the number of observations binned ({}), at least 1", total));
    }
    if (hist.resolution < 0.0) h["resolution"].Fail("a resolution >= 0");
    data.histogram = std::move(hist);
  }
  if (!plot["autocorrelation"].IsNull()) {
    const JsonCursor a = plot["autocorrelation"];
    AutocorrelationPlotData ac;
    ac.n = a["n"].Integer();
    ac.band = a["band"].Number();
    ac.rho = a["rho"].Numbers();
    if (ac.n < 1) a["n"].Fail("a number of observations >= 1");
    if (!(ac.band > 0.0)) a["band"].Fail("a band > 0");
    data.autocorrelation = std::move(ac);
  }
  return data;
}

}  // namespace metro
