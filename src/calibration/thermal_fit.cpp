// FitThermalBias runs these stages (thermal_fit.hpp):
//   glitches   FindTemperatureGlitches    read errors found and left out, with their lines
//   legs       SplitLegs                  heating / cooling about the hottest sample
//   bins       BinMeans                   per (leg, temperature bin) means
//   order      ChooseOrder                nested F-tests on the bin means
//   solution   SolveAxis                  coefficients, covariance, hysteresis
#include "metro/calibration/thermal_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

namespace metro {

bool ThermalFitOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (!(bin_width_c > 0)) return fail("bin_width_c must be > 0");
  if (min_samples_per_bin < 2) return fail("min_samples_per_bin must be >= 2");
  if (max_order < 1 || max_order > 4) return fail("max_order must be 1 .. 4");
  if (order < 0 || order > max_order) return fail("order must be 0 (auto) .. max_order");
  if (!(alpha > 0 && alpha < 1)) return fail("alpha must be in (0, 1)");
  if (!(span_per_order_c > 0 && glitch_c > 0 && min_leg_span_c > 0)) {
    return fail("span_per_order_c, glitch_c and min_leg_span_c must be > 0");
  }
  if (glitch_window < 1) return fail("glitch_window must be >= 1");
  return true;
}

std::vector<size_t> FindTemperatureGlitches(const std::vector<double>& temp_c, double glitch_c,
                                            int window) {
  std::vector<size_t> out;
  const size_t n = temp_c.size(), w = static_cast<size_t>(window);
  std::vector<double> around;
  for (size_t i = 0; i < n; ++i) {
    around.clear();
    for (size_t k = i > w ? i - w : 0; k < std::min(n, i + w + 1); ++k) {
      if (k != i && std::isfinite(temp_c[k])) around.push_back(temp_c[k]);
    }
    if (around.empty()) continue;
    auto mid = around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2);
    std::nth_element(around.begin(), mid, around.end());
    if (!std::isfinite(temp_c[i]) || std::abs(temp_c[i] - *mid) > glitch_c) out.push_back(i);
  }
  return out;
}

namespace {

// Removes the nominal 1 g from the accelerometer axis that reads it (ThermalSamplesFromTag).
Status RemoveGravity(double accel_fs_g, ThermalSamples* s) {
  const std::optional<double> scale = NominalScale(ImuSensor::kAccel, "LSB", accel_fs_g);
  if (!scale) return MakeError(fmt::format("accel_fs_g {} is not a full scale", accel_fs_g));
  const double one_g_lsb = 1.0 / *scale;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) {
    double sum = 0;
    for (double v : s->values[a]) sum += v;
    mean[a] = s->values[a].empty() ? 0.0 : sum / static_cast<double>(s->values[a].size());
  }
  Eigen::Index axis = 0;
  mean.cwiseAbs().maxCoeff(&axis);
  if (std::abs(std::abs(mean[axis]) - one_g_lsb) > 0.15 * one_g_lsb) {
    return MakeError(fmt::format(
        "{}: the largest mean reading, {:.0f} LSB on {}, is not 1 g ({:.0f} LSB at +-{} g) "
        "within 15 %: a thermal fit takes one static pose on a face",
        s->what, mean[axis], "xyz"[axis], one_g_lsb, accel_fs_g));
  }
  const double g = mean[axis] > 0 ? one_g_lsb : -one_g_lsb;
  for (double& v : s->values[static_cast<size_t>(axis)]) v -= g;
  return Status::Ok();
}

}  // namespace

Result<ThermalSamples> ThermalSamplesFromTag(const Tag& tag, ImuSensor sensor,
                                             const std::string& path, double accel_fs_g) {
  ThermalSamples s;
  s.what = fmt::format("{}: sensor {} {}", path, tag.sensor, ImuSensorName(sensor));
  std::string have;
  for (const Quantity& q : tag.quantities) have += (have.empty() ? "" : ", ") + q.name;
  const Quantity* temp = tag.Find("temp_c");
  if (temp == nullptr) {
    return MakeError(fmt::format(
        "{}: no temp_c column: a thermal fit needs the die temperature per sample (columns: {})",
        s.what, have));
  }
  const std::vector<std::string> names = InputColumns(sensor, "LSB");
  for (int a = 0; a < 3; ++a) {
    const Quantity* q = tag.Find(names[a]);
    if (q == nullptr) {
      return MakeError(fmt::format("{}: no {} column: a thermal fit reads raw counts (columns: {})",
                                   s.what, names[a], have));
    }
    s.values[a] = q->values;
  }
  s.temp_c = temp->values;
  s.lines.assign(tag.line.begin(), tag.line.end());
  if (sensor == ImuSensor::kAccel) {
    if (Status g = RemoveGravity(accel_fs_g, &s); !g.ok()) return g.error();
  }
  return s;
}

double ThermalAxisFit::BiasAt(double temp_c, double t_ref_c) const {
  const double x = temp_c - t_ref_c;
  double b = 0;
  for (int j = order; j >= 0; --j) b = b * x + coefficients[j];
  return b;
}

double ThermalAxisFit::UBiasAt(double temp_c, double t_ref_c) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(covariance.rows());
  const double x = temp_c - t_ref_c;
  for (int j = 0; j <= order; ++j) g[j] = std::pow(x, j);
  return std::sqrt(std::max(0.0, g.dot(covariance * g)));  // JCGM 100:2008 5.2.2
}

namespace {

struct Bins {
  std::vector<double> temp_c;  // Mean temperature of each bin.
  // Central moments of the bin's temperatures, mean((T - mean T)^k), k = 0..4, so that the
  // design row is the bin mean of the powers (exact for a polynomial), not powers of the mean.
  std::vector<std::array<double, 5>> moments;
  std::vector<double> leg;  // +1 heating, -1 cooling, 0 one leg only.
  std::array<std::vector<double>, 3> mean;
};

// +1 before the hottest sample, -1 after it, when each side spans min_leg_span_c; else all 0.
std::vector<int> SplitLegs(const std::vector<double>& temp_c, double min_leg_span_c) {
  std::vector<int> leg(temp_c.size(), 0);
  if (temp_c.empty()) return leg;
  const auto hot = std::max_element(temp_c.begin(), temp_c.end());
  const double rise = *hot - *std::min_element(temp_c.begin(), hot + 1);
  const double fall = *hot - *std::min_element(hot, temp_c.end());
  if (rise < min_leg_span_c || fall < min_leg_span_c) return leg;
  const size_t k = static_cast<size_t>(hot - temp_c.begin());
  for (size_t i = 0; i < leg.size(); ++i) leg[i] = i <= k ? 1 : -1;
  return leg;
}

Bins BinMeans(const ThermalSamples& s, const std::vector<int>& leg, const std::vector<bool>& use,
              const ThermalFitOptions& o) {
  struct Sum {
    double temp = 0;
    std::array<double, 3> v{};
    std::array<double, 5> m{};
    int n = 0;
  };
  std::map<std::pair<int, long>, Sum> sums;
  auto key = [&](size_t i) {
    return std::make_pair(leg[i], std::lround(std::floor(s.temp_c[i] / o.bin_width_c)));
  };
  for (size_t i = 0; i < s.temp_c.size(); ++i) {
    if (!use[i]) continue;
    Sum& b = sums[key(i)];
    b.temp += s.temp_c[i];
    for (int a = 0; a < 3; ++a) b.v[a] += s.values[a][i];
    ++b.n;
  }
  for (size_t i = 0; i < s.temp_c.size(); ++i) {
    if (!use[i]) continue;
    Sum& b = sums[key(i)];
    const double d = s.temp_c[i] - b.temp / b.n;
    for (int k = 0; k < 5; ++k) b.m[k] += std::pow(d, k);
  }
  Bins out;
  for (const auto& [k, b] : sums) {
    if (b.n < o.min_samples_per_bin) continue;
    out.temp_c.push_back(b.temp / b.n);
    std::array<double, 5> m;
    for (int j = 0; j < 5; ++j) m[j] = b.m[j] / b.n;
    out.moments.push_back(m);
    out.leg.push_back(k.first);
    for (int a = 0; a < 3; ++a) out.mean[a].push_back(b.v[a] / b.n);
  }
  return out;
}

// Columns mean(z^j), j = 0..order, over each bin (z = (T - t_ref_c) / scale_c; from the
// bin's mean and central moments, binomial expansion) and leg / 2 when legs.
Eigen::MatrixXd Design(const Bins& b, int order, bool legs, double t_ref_c, double scale_c) {
  static const double kBinomial[5][5] = {
      {1, 0, 0, 0, 0}, {1, 1, 0, 0, 0}, {1, 2, 1, 0, 0}, {1, 3, 3, 1, 0}, {1, 4, 6, 4, 1}};
  const Eigen::Index n = static_cast<Eigen::Index>(b.temp_c.size());
  Eigen::MatrixXd x(n, order + 1 + (legs ? 1 : 0));
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = b.temp_c[i] - t_ref_c;
    const std::array<double, 5>& m = b.moments[i];
    for (int j = 0; j <= order; ++j) {
      double sum = 0;  // mean((d + e)^j) = sum_k C(j, k) d^(j-k) mean(e^k)
      for (int k = 0; k <= j; ++k) sum += kBinomial[j][k] * std::pow(d, j - k) * m[k];
      x(i, j) = sum / std::pow(scale_c, j);
    }
    if (legs) x(i, order + 1) = 0.5 * b.leg[i];
  }
  return x;
}

struct Solution {
  Eigen::VectorXd beta;
  Eigen::MatrixXd xtx_inv;
  double rss = 0;
  double dof = 0;
};

Solution Solve(const Eigen::MatrixXd& x, const Eigen::VectorXd& y) {
  Solution s;
  s.beta = x.colPivHouseholderQr().solve(y);
  s.rss = (y - x * s.beta).squaredNorm();
  s.dof = static_cast<double>(x.rows() - x.cols());
  s.xtx_inv = (x.transpose() * x).ldlt().solve(Eigen::MatrixXd::Identity(x.cols(), x.cols()));
  return s;
}

// Nested F-tests of each order p against p - 1 (thermal_fit.hpp); `tests` gets each statistic.
// The chosen order is the highest whose test is significant at alpha / (max_order - 1)
// (Bonferroni over the tests), so a small intermediate term does not stop the climb.
int ChooseOrder(const Bins& b, const Eigen::VectorXd& y, int max_order, bool legs, double t_ref_c,
                double scale_c, double alpha, std::vector<OrderTest>* tests) {
  Solution prev = Solve(Design(b, 1, legs, t_ref_c, scale_c), y);
  int chosen = 1;
  const double level = alpha / std::max(1, max_order - 1);
  for (int p = 2; p <= max_order; ++p) {
    const Solution next = Solve(Design(b, p, legs, t_ref_c, scale_c), y);
    OrderTest t;
    t.order = p;
    t.dof = next.dof;
    t.f = next.rss > 0 ? std::max(0.0, prev.rss - next.rss) / (next.rss / next.dof)
                       : std::numeric_limits<double>::infinity();
    t.p_value =
        std::isfinite(t.f)
            ? boost::math::cdf(boost::math::complement(boost::math::fisher_f(1.0, next.dof), t.f))
            : 0.0;
    tests->push_back(t);
    if (t.p_value < level) chosen = p;
    prev = next;
  }
  return chosen;
}

ThermalAxisFit SolveAxis(const Bins& b, int axis, int order, bool legs, double t_ref_c,
                         double scale_c) {
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(
      b.mean[axis].data(), static_cast<Eigen::Index>(b.mean[axis].size()));
  const Solution s = Solve(Design(b, order, legs, t_ref_c, scale_c), y);
  const Eigen::Index k = s.beta.size();
  // Back to degC: c_j = beta_j / scale^j, V = D (s^2 (X'X)^-1) D (JCGM 100:2008 H.3.4).
  Eigen::VectorXd d = Eigen::VectorXd::Ones(k);
  for (int j = 0; j <= order; ++j) d[j] = std::pow(scale_c, -j);
  ThermalAxisFit f;
  f.order = order;
  f.dof = s.dof;
  const double s2 = s.dof > 0 ? s.rss / s.dof : 0.0;
  f.covariance = d.asDiagonal() * (s2 * s.xtx_inv) * d.asDiagonal();
  const Eigen::VectorXd c = d.cwiseProduct(s.beta);
  f.coefficients = c.head(order + 1);
  f.u = f.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  f.residual_rms = std::sqrt(s.rss / static_cast<double>(y.size()));
  f.has_hysteresis = legs;
  if (legs) {
    f.hysteresis = c[k - 1];
    f.u_hysteresis = f.u[k - 1];
  }
  return f;
}

}  // namespace

Result<ThermalFit> FitThermalBias(const ThermalSamples& s, const ThermalFitOptions& o,
                                  double t_ref_c) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError(s.what + ": invalid thermal fit options: " + why);
  ThermalFit fit;
  std::vector<bool> use(s.temp_c.size(), true);
  for (size_t i : FindTemperatureGlitches(s.temp_c, o.glitch_c, o.glitch_window)) {
    use[i] = false;
    fit.excluded_lines.push_back(i < s.lines.size() ? s.lines[i] : static_cast<int64_t>(i));
  }
  std::vector<double> kept;
  for (size_t i = 0; i < use.size(); ++i) {
    if (use[i]) kept.push_back(s.temp_c[i]);
  }
  const std::vector<int> kept_leg =
      o.separate_legs ? SplitLegs(kept, o.min_leg_span_c) : std::vector<int>(kept.size(), 0);
  std::vector<int> leg(use.size(), 0);
  for (size_t i = 0, k = 0; i < use.size(); ++i) {
    if (use[i]) leg[i] = kept_leg[k++];
  }
  const Bins b = BinMeans(s, leg, use, o);
  fit.bins = static_cast<int>(b.temp_c.size());
  fit.legs = std::any_of(leg.begin(), leg.end(), [](int l) { return l != 0; });
  if (b.temp_c.empty()) {
    return MakeError(fmt::format("{}: no temperature bin of {} degC holds {} samples", s.what,
                                 o.bin_width_c, o.min_samples_per_bin));
  }
  fit.t_min_c = *std::min_element(b.temp_c.begin(), b.temp_c.end());
  fit.t_max_c = *std::max_element(b.temp_c.begin(), b.temp_c.end());
  const double span = fit.t_max_c - fit.t_min_c;
  const int needed = std::max(1, o.order);
  // Each order needs its span and at least two bins more than parameters (a residual dof).
  const int by_span = static_cast<int>(std::floor(span / o.span_per_order_c + 1e-9));
  const int by_bins = fit.bins - 3 - (fit.legs ? 1 : 0);
  const int max_order = std::min({o.max_order, by_span, by_bins});
  if (max_order < needed) {
    const auto [lo, hi] = std::minmax_element(kept.begin(), kept.end());
    return MakeError(fmt::format(
        "{}: the temperature spans {:.2f} degC between bin means ({:.2f} .. {:.2f} degC, {} "
        "bins of {} degC; samples {:.2f} .. {:.2f} degC); a bias fit of order {} needs at least "
        "{:.1f} degC and {} bins",
        s.what, span, fit.t_min_c, fit.t_max_c, fit.bins, o.bin_width_c, *lo, *hi, needed,
        o.span_per_order_c * needed, needed + 3 + (fit.legs ? 1 : 0)));
  }
  fit.t_ref_c = std::isnan(t_ref_c) ? 0.5 * (fit.t_min_c + fit.t_max_c) : t_ref_c;
  const double scale_c = std::max(0.5 * span, 1e-3);
  for (int a = 0; a < 3; ++a) {
    const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(
        b.mean[a].data(), static_cast<Eigen::Index>(b.mean[a].size()));
    std::vector<OrderTest> tests;
    const int order =
        o.order > 0 ? o.order
                    : ChooseOrder(b, y, max_order, fit.legs, fit.t_ref_c, scale_c, o.alpha, &tests);
    fit.axes[a] = SolveAxis(b, a, order, fit.legs, fit.t_ref_c, scale_c);
    fit.axes[a].tests = std::move(tests);
  }
  return fit;
}

Result<ThermalTagFit> FitThermalTag(const Tag& tag, const std::string& path,
                                    const ThermalFitOptions& o) {
  ThermalTagFit out;
  out.sensor = tag.sensor;
  out.path = path;
  for (ImuSensor sensor : {ImuSensor::kAccel, ImuSensor::kGyro}) {
    Result<ThermalSamples> s = ThermalSamplesFromTag(tag, sensor, path);
    if (!s.ok()) return s.error();
    Result<ThermalFit> f = FitThermalBias(s.value(), o, std::nan(""));
    if (!f.ok()) return f.error();
    (sensor == ImuSensor::kAccel ? out.accel : out.gyro) = std::move(f).value();
  }
  return out;
}

namespace {

using OrderedJson = nlohmann::ordered_json;

OrderedJson MatrixJson(const Eigen::MatrixXd& m) {
  OrderedJson rows = OrderedJson::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    std::vector<double> row(static_cast<size_t>(m.cols()));
    for (Eigen::Index c = 0; c < m.cols(); ++c) row[static_cast<size_t>(c)] = m(r, c);
    rows.push_back(row);
  }
  return rows;
}

OrderedJson AxisJson(const ThermalAxisFit& f) {
  static const char* kNames[5] = {"bias", "bias_per_c", "bias_per_c2", "bias_per_c3",
                                  "bias_per_c4"};
  OrderedJson j = {{"order", f.order}};
  std::vector<std::string> params;
  for (int k = 0; k <= f.order; ++k) {
    j[kNames[k]] = f.coefficients[k];
    j[std::string(kNames[k]) + "_u"] = f.u[k];
    params.push_back(kNames[k]);
  }
  if (f.has_hysteresis) {
    j["hysteresis"] = f.hysteresis;
    j["hysteresis_u"] = f.u_hysteresis;
    params.push_back("hysteresis");
  }
  j["parameters"] = params;
  j["covariance"] = MatrixJson(f.covariance);
  j["residual_rms"] = f.residual_rms;
  j["dof"] = f.dof;
  OrderedJson tests = OrderedJson::array();
  for (const OrderTest& t : f.tests) {
    tests.push_back({{"order", t.order}, {"f", t.f}, {"dof", t.dof}, {"p_value", t.p_value}});
  }
  j["order_tests"] = tests;
  return j;
}

OrderedJson SensorJson(const ThermalFit& f, const char* input_unit) {
  OrderedJson axes = OrderedJson::array();
  for (const ThermalAxisFit& a : f.axes) axes.push_back(AxisJson(a));
  return {{"input_unit", input_unit},
          {"t_ref_c", f.t_ref_c},
          {"t_valid_min_c", f.t_min_c},
          {"t_valid_max_c", f.t_max_c},
          {"bins", f.bins},
          {"legs", f.legs ? "heating and cooling" : "one"},
          {"excluded_temp_lines", f.excluded_lines},
          {"axes", axes}};
}

}  // namespace

std::string ThermalFitJson(const std::vector<ThermalTagFit>& fits, const ThermalFitOptions& o) {
  OrderedJson tags = OrderedJson::array();
  for (const ThermalTagFit& t : fits) {
    tags.push_back({{"sensor", t.sensor},
                    {"input", t.path},
                    {"accel", SensorJson(t.accel, "LSB")},
                    {"gyro", SensorJson(t.gyro, "LSB")}});
  }
  OrderedJson j = {
      {"schema", "metro.thermal-fit/1"},
      {"model_equation",
       "b(T) = bias + bias_per_c x + bias_per_c2 x^2 + bias_per_c3 x^3 + bias_per_c4 x^4 "
       "[+ leg hysteresis / 2], x = T - t_ref_c, leg +1 heating, -1 cooling (docs/thermal.md)"},
      {"method",
       "ordinary least squares on temperature-bin means (uniform in temperature); covariance "
       "s^2 (X'X)^-1 (JCGM 100:2008 H.3); order by nested F-tests"},
      {"bin_width_c", o.bin_width_c},
      {"alpha", o.alpha},
      {"tags", tags}};
  return j.dump(2) + "\n";
}

}  // namespace metro
