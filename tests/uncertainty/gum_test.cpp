// GUM framework against the published examples of JCGM 100:2008 Annex H.
#include "metro/uncertainty/gum.hpp"

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/budget_report.hpp"

namespace metro {
namespace {

Budget Load(const std::string& name) {
  auto b = LoadBudget(std::string(METRO_SOURCE_DIR) + "/datasets/budgets/" + name);
  if (!b.ok()) FAIL(b.error().ToString());
  return b.value();
}

Budget Parse(const std::string& text) {
  auto b = ParseBudget(text, "test.json");
  if (!b.ok()) FAIL(b.error().ToString());
  return b.value();
}

TEST_CASE("GUM H.1 end gauge first order", "[uncertainty][gum]") {
  const Budget budget = Load("gum_h1_end_gauge.json");
  CHECK(budget.gum.truncate_dof);  // as H.1.6; here the fractional nu_eff is checked
  GumOptions fractional = budget.gum;
  fractional.truncate_dof = false;
  auto r = EvaluateGum(budget, fractional);
  REQUIRE(r.ok());
  const GumResult& g = r.value();
  // JCGM 100 H.1: l = 50.000 838 mm, u_c = 31.664 nm (printed 32 nm), nu_eff = 16.75
  // (printed 16 after G.6.4 truncation), k99 = 2.92, U99 = 93 nm. Deterministic, with exact
  // sensitivity coefficients.
  CHECK(g.value == Approx(50000838.0).margin(0.5));
  CHECK(g.u == Approx(31.66388).margin(5e-4));
  CHECK(g.dof_eff == Approx(16.7519).margin(2e-3));
  // Fractional nu_eff: k lies between the table values t_99(17) = 2.898 and t_99(16) = 2.921.
  CHECK(g.k > 2.898);
  CHECK(g.k < 2.921);
  // Sensitivities of H.1 Table H.1: c(da) = -ls theta = 5.000 062 3e6 nm/degC,
  // c(dth) = -ls als = -575.007 nm/degC, c(als) = c(theta) = 0.
  for (const BudgetLine& line : g.budget) {
    if (line.name == "da") CHECK(line.sensitivity == Approx(5.0000623e6).epsilon(1e-6));
    if (line.name == "dth") CHECK(line.sensitivity == Approx(-575.007).epsilon(1e-6));
    if (line.name == "als") CHECK(line.sensitivity == Approx(0.0).margin(1e-3));
    if (line.name == "dlt") CHECK(line.contribution == Approx(0.0).margin(1e-9));
  }
  // Sorted by contribution, ls (25 nm) first, then dth (16.6 nm).
  REQUIRE(g.budget.size() == 9);
  CHECK(g.budget[0].name == "ls");
  CHECK(g.budget[1].name == "dth");
  double percent = 0.0;
  for (const BudgetLine& line : g.budget) percent += line.percent;
  CHECK(percent == Approx(100.0).margin(1e-9));
}

TEST_CASE("GUM H.1 with truncated dof and second-order terms", "[uncertainty][gum]") {
  const Budget budget = Load("gum_h1_end_gauge.json");
  GumOptions options = budget.gum;
  options.truncate_dof = true;
  auto truncated = EvaluateGum(budget, options);
  REQUIRE(truncated.ok());
  CHECK(truncated.value().dof_eff == 16.0);  // JCGM 100 G.6.4 and H.1.6
  // H.1.6: k99 = t_99(16) = 2.92, U99 = 2.92 x 32 nm = 93 nm with the rounded u_c; with
  // the unrounded u_c = 31.664 nm, U = 2.920782 x 31.66388 = 92.48 nm.
  CHECK(truncated.value().k == Approx(2.920782).margin(1e-5));
  CHECK(truncated.value().expanded == Approx(92.484).margin(0.005));
  CHECK(std::round(truncated.value().k * std::round(truncated.value().u)) == 93.0);
  options.truncate_dof = false;
  options.second_order = true;
  auto second = EvaluateGum(budget, options);
  REQUIRE(second.ok());
  // H.1.7: with the second-order terms u_c = 34 nm. Closed form (independent inputs): the
  // only non-zero second derivatives are d2l/(dda dtheta) = d2l/(dals ddth) = -ls, so
  // u^2 = u1^2 + ls^2 u(da)^2 u(theta)^2 + ls^2 u(als)^2 u(dth)^2 with u(theta)^2 =
  // 0.2^2 + 0.5^2/2 spread over th0 and dlt.
  const double ls = 50000623.0;
  const double u_da = 1e-6 / std::sqrt(3.0);
  const double u_als = 2e-6 / std::sqrt(3.0);
  const double u_dth = 0.05 / std::sqrt(3.0);
  const double u_theta2 = 0.04 + 0.125;
  const double u1 = second.value().u_first_order;
  const double expected = std::sqrt(u1 * u1 + ls * ls * u_da * u_da * u_theta2 +
                                    ls * ls * u_als * u_als * u_dth * u_dth);
  CHECK(second.value().u == Approx(expected).epsilon(1e-6));
  CHECK(std::round(second.value().u) == 34.0);
}

// JCGM 100 H.2: simultaneous resistance and reactance from five simultaneous observations of
// V, I (mA) and phi (Table H.2). Published (H.2.3, approach 1): R = 127.732 ohm, u = 0.071;
// X = 219.847, u = 0.295; Z = 254.260, u = 0.236. The correlation coefficients are computed
// here from the observations (the printed -0.36, 0.86, -0.65 are rounded).
const double kV[5] = {5.007, 4.994, 5.005, 4.990, 4.999};
const double kI[5] = {19.663, 19.639, 19.640, 19.685, 19.678};
const double kPhi[5] = {1.0456, 1.0438, 1.0468, 1.0428, 1.0433};

double SampleR(const double* a, const double* b) {
  double ma = 0, mb = 0;
  for (int k = 0; k < 5; ++k) ma += a[k] / 5, mb += b[k] / 5;
  double sab = 0, saa = 0, sbb = 0;
  for (int k = 0; k < 5; ++k) {
    sab += (a[k] - ma) * (b[k] - mb);
    saa += (a[k] - ma) * (a[k] - ma);
    sbb += (b[k] - mb) * (b[k] - mb);
  }
  return sab / std::sqrt(saa * sbb);  // JCGM 100 5.2.3 / C.3.6
}

std::string H2(const std::string& model) {
  const auto values = [](const double* x) {
    std::string s;
    for (int k = 0; k < 5; ++k) s += (k ? ", " : "") + std::to_string(x[k]);
    return "{\"values\": [" + s + "]}";
  };
  return R"({"measurand": {"name": "y", "unit": "ohm", "model": ")" + model + R"("},
    "inputs": [{"name": "V", "type_a": )" +
         values(kV) + R"(},
               {"name": "I", "type_a": )" +
         values(kI) + R"(},
               {"name": "phi", "type_a": )" +
         values(kPhi) + R"(}],
    "correlations": [{"a": "V", "b": "I", "r": )" +
         std::to_string(SampleR(kV, kI)) + R"(},
                     {"a": "V", "b": "phi", "r": )" +
         std::to_string(SampleR(kV, kPhi)) + R"(},
                     {"a": "I", "b": "phi", "r": )" +
         std::to_string(SampleR(kI, kPhi)) + R"(}],
    "monte_carlo": false})";
}

TEST_CASE("GUM H.2 resistance reactance impedance", "[uncertainty][gum]") {
  CHECK(SampleR(kV, kI) == Approx(-0.36).margin(0.005));  // As printed in H.2.
  CHECK(SampleR(kV, kPhi) == Approx(0.86).margin(0.005));
  CHECK(SampleR(kI, kPhi) == Approx(-0.65).margin(0.005));
  struct Case {
    const char* model;
    double value;
    double u;
  };
  for (const Case& c :
       {Case{"V/(I*1e-3)*cos(phi)", 127.732, 0.071}, Case{"V/(I*1e-3)*sin(phi)", 219.847, 0.295},
        Case{"V/(I*1e-3)", 254.260, 0.236}}) {
    INFO(c.model);
    auto r = EvaluateGum(Parse(H2(c.model)));
    REQUIRE(r.ok());
    // Half a unit of the last published digit (u: +-0.6e-3, the GUM truncates 0.2956).
    CHECK(r.value().value == Approx(c.value).margin(5e-4));
    CHECK(r.value().u == Approx(c.u).margin(6e-4));
    // One ensemble of means from the same 5 observations: nu = 4 (group policy).
    CHECK(r.value().dof_eff == Approx(4.0).margin(1e-12));
    CHECK(r.value().correlated);
  }
  // Independent check of u(R) with the analytic Jacobian and the sample covariance.
  double mean[3] = {0, 0, 0};
  const double* data[3] = {kV, kI, kPhi};
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < 5; ++k) mean[a] += data[a][k] / 5;
  }
  double cov[3][3] = {};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      for (int k = 0; k < 5; ++k) cov[a][b] += (data[a][k] - mean[a]) * (data[b][k] - mean[b]) / 20;
    }
  }
  const double v = mean[0], i = mean[1] * 1e-3, phi = mean[2];
  const double grad[3] = {std::cos(phi) / i, -v * std::cos(phi) / (i * i) * 1e-3,
                          -v * std::sin(phi) / i};
  double var = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) var += grad[a] * grad[b] * cov[a][b];
  }
  auto r = EvaluateGum(Parse(H2("V/(I*1e-3)*cos(phi)")));
  REQUIRE(r.ok());
  CHECK(r.value().u == Approx(std::sqrt(var)).epsilon(1e-5));
}

TEST_CASE("GUM H.3 thermometer correction at 30 degC", "[uncertainty][gum]") {
  // H.3.4: b(30 degC) = y1 + y2 (30 - 20) = -0.1494 degC, u = 0.0041 degC, from
  // y1 = -0.1712 (s 0.0029), y2 = 0.00218 (s 0.00067), r = -0.930, nu = 9.
  auto r = EvaluateGum(Parse(R"j({"measurand": {"name": "b", "unit": "degC",
      "model": "y1 + y2*(30 - 20)"},
    "inputs": [{"name": "y1", "value": -0.1712, "u": 0.0029, "dof": 9},
               {"name": "y2", "value": 0.00218, "u": 0.00067, "dof": 9}],
    "correlations": [{"a": "y1", "b": "y2", "r": -0.930}], "monte_carlo": false})j"));
  REQUIRE(r.ok());
  CHECK(r.value().value == Approx(-0.1494).margin(5e-5));
  const double closed =
      std::sqrt(0.0029 * 0.0029 + 100 * 0.00067 * 0.00067 + 2 * 10 * -0.930 * 0.0029 * 0.00067);
  CHECK(r.value().u == Approx(closed).epsilon(1e-7));
  CHECK(r.value().u == Approx(0.0041).margin(5e-5));
  CHECK(r.value().dof_eff == Approx(9.0));
}

TEST_CASE("A combined variance beyond double precision is an error, not u = inf",
          "[uncertainty][gum]") {
  // u = 1e308: u^2 overflows (issue #20: the report said u = inf, exit 0).
  Budget huge = Parse(R"({"measurand": {"name": "y", "model": "x"},
    "inputs": [{"name": "x", "value": 1.0, "u": 1e308}], "monte_carlo": false})");
  auto r = EvaluateGum(huge);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().ToString().find("the combined variance sum c_i c_j u_i u_j r_ij overflows "
                                  "double precision") != std::string::npos);
  // u = 1e150 squares to 1e300: evaluated exactly.
  Budget large = Parse(R"({"measurand": {"name": "y", "model": "x"},
    "inputs": [{"name": "x", "value": 1.0, "u": 1e150}], "monte_carlo": false})");
  auto ok = EvaluateGum(large);
  REQUIRE(ok.ok());
  CHECK(ok.value().u == Approx(1e150).epsilon(1e-9));
}

TEST_CASE("Budget table without a model and the dof policies", "[uncertainty][gum]") {
  // y = 2 a + b: u^2 = 4 u_a^2 + u_b^2 + 2 * 2 * r u_a u_b.
  const std::string text = R"({"measurand": {"name": "y"},
    "inputs": [{"name": "a", "value": 1.0, "u": 0.3, "dof": 5, "sensitivity": 2.0},
               {"name": "b", "value": 4.0, "u": 0.4, "dof": 10, "sensitivity": 1.0},
               {"name": "c", "value": 0.0, "u": 0.5, "dof": 20, "sensitivity": 1.0}],
    "correlations": [{"a": "a", "b": "b", "r": 0.5}], "monte_carlo": false})";
  Budget budget = Parse(text);
  auto group = EvaluateGum(budget);
  REQUIRE(group.ok());
  CHECK(group.value().value == Approx(6.0));
  const double ug2 = 0.36 + 0.16 + 2 * 2 * 0.5 * 0.3 * 0.4;
  const double uc2 = ug2 + 0.25;
  CHECK(group.value().u == Approx(std::sqrt(uc2)));
  // Group {a, b}: u_g^2 at min(5, 10) dof; c alone at 20.
  CHECK(group.value().dof_eff == Approx(uc2 * uc2 / (ug2 * ug2 / 5 + 0.25 * 0.25 / 20)));
  budget.gum.correlated_dof = CorrelatedDofPolicy::kIgnore;
  auto ignore = EvaluateGum(budget);
  REQUIRE(ignore.ok());
  CHECK(ignore.value().dof_eff ==
        Approx(uc2 * uc2 / (std::pow(0.6, 4) / 5 + std::pow(0.4, 4) / 10 + std::pow(0.5, 4) / 20)));
  CHECK(ignore.value().dof_note.find("ignore") != std::string::npos);
  budget.gum.correlated_dof = CorrelatedDofPolicy::kReject;
  auto reject = EvaluateGum(budget);
  REQUIRE_FALSE(reject.ok());
  CHECK(reject.error().message.find("inputs 'a' and 'b' are correlated") != std::string::npos);
}

TEST_CASE("Coverage factor from Boost students_t with fractional dof", "[uncertainty][gum]") {
  // Tabulated t quantiles (JCGM 100 Table G.2): t_95(10) = 2.23, t_99(16) = 2.92,
  // t_95(inf) = 1.96.
  CHECK(CoverageFactor(0.95, 10) == Approx(2.228139).margin(1e-6));
  CHECK(CoverageFactor(0.99, 16) == Approx(2.920782).margin(1e-6));
  CHECK(CoverageFactor(0.95, std::numeric_limits<double>::infinity()) ==
        Approx(1.959964).margin(1e-6));
  // Fractional dof lies between its neighbours.
  CHECK(CoverageFactor(0.99, 16.75) < CoverageFactor(0.99, 16));
  CHECK(CoverageFactor(0.99, 16.75) > CoverageFactor(0.99, 17));
}

// ---------------------------------------------------------------- exact derivatives (#22)

// A one-model budget with the given inputs (JSON array body) and Monte Carlo settings.
Budget Model(const std::string& model, const std::string& inputs, int64_t trials = 0) {
  return Parse(
      R"({"measurand": {"name": "y", "model": ")" + model + R"("}, "inputs": [)" + inputs + "]" +
      (trials > 0 ? R"(, "monte_carlo": {"trials": )" + std::to_string(trials) + R"(, "seed": 3})"
                  : std::string(R"(, "monte_carlo": {"enabled": false})")) +
      "}");
}

TEST_CASE("Sensitivity coefficients are exact where rounding erased central differences",
          "[uncertainty][gum][derivatives]") {
  // issue #22: steps of 1e-3 u_i vanish beside |x_i|: y = fm at 1e7 +- 1e-6 Hz gave u_c
  // 1.86e-6 (+86 %), at 1e9 +- 1e-3 Hz c = 0.954.
  for (const auto& [x, u] : {std::pair<double, double>{1e7, 1e-6}, {1e9, 1e-3}}) {
    const Budget b = Model("fm", fmt::format(R"({{"name": "fm", "value": {}, "u": {}}})", x, u));
    auto r = EvaluateGum(b);
    REQUIRE(r.ok());
    INFO("fm = " << x << " +- " << u);
    CHECK(r.value().derivatives == "exact (symbolic, GiNaC)");
    CHECK(r.value().budget[0].sensitivity == 1.0);
    CHECK(r.value().u == Approx(u).epsilon(1e-12));
  }
  // y = fm (1 + dref) at 1 GHz, u(dref) = 1e-12: c(fm) = 1 + dref, c(dref) = fm.
  const Budget ref = Model("fm*(1 + dref)",
                           R"({"name": "fm", "value": 1e9, "u": 1e-3},
                              {"name": "dref", "value": 2e-12, "u": 1e-12})",
                           200000);
  auto g = EvaluateGum(ref);
  REQUIRE(g.ok());
  for (const BudgetLine& line : g.value().budget) {
    INFO(line.name);
    CHECK(line.sensitivity == Approx(line.name == "fm" ? 1.0 + 2e-12 : 1e9).epsilon(1e-12));
  }
  // u_c^2 = (1 + dref)^2 u(fm)^2 + fm^2 u(dref)^2 = 1e-6 + 1e-6.
  CHECK(g.value().u == Approx(std::sqrt(2e-6)).epsilon(1e-12));
  // Linear in each input: the GUF is validated against the Monte Carlo (it was not).
  auto e = EvaluateBudget(ref);
  REQUIRE(e.ok());
  REQUIRE(e.value().validation);
  CHECK(e.value().validation->validated);
  // A 50 mm gauge in nm with its thermal expansion: l = ls (1 + als dt); c(dt) = ls als.
  const Budget gauge = Model("ls*(1 + als*dt)",
                             R"({"name": "ls", "value": 50000623, "u": 25},
                                {"name": "als", "value": 11.5e-6, "u": 1e-6},
                                {"name": "dt", "value": 0.0003, "u": 1e-9})");
  auto l = EvaluateGum(gauge);
  REQUIRE(l.ok());
  for (const BudgetLine& line : l.value().budget) {
    INFO(line.name);
    const double want = line.name == "ls"    ? 1.0 + 11.5e-6 * 0.0003
                        : line.name == "als" ? 50000623.0 * 0.0003
                                             : 50000623.0 * 11.5e-6;
    CHECK(line.sensitivity == Approx(want).epsilon(1e-12));
  }
}

TEST_CASE("Second-order terms from exact derivatives match their closed forms",
          "[uncertainty][gum][derivatives]") {
  // JCGM 100 5.1.2 note: u^2 = sum c_i^2 u_i^2 + sum_ij (f_ij^2 / 2 + f_i f_ijj) u_i^2 u_j^2.
  const auto second_order =
      [](const std::vector<double>& f1, const std::vector<std::vector<double>>& f2,
         const std::vector<std::vector<double>>& f3, const std::vector<double>& u) {
        double v = 0.0;
        for (size_t i = 0; i < u.size(); ++i) v += f1[i] * f1[i] * u[i] * u[i];
        for (size_t i = 0; i < u.size(); ++i) {
          for (size_t j = 0; j < u.size(); ++j) {
            v += (0.5 * f2[i][j] * f2[i][j] + f1[i] * f3[i][j]) * u[i] * u[i] * u[j] * u[j];
          }
        }
        return std::sqrt(v);
      };
  {
    // P = V^2 / R, V = 10 +- 0.5 V, R = 4 +- 0.2 ohm. f3[i][j] = d3f / dx_i dx_j^2.
    const double v = 10, r = 4, uv = 0.5, ur = 0.2;
    Budget b = Model("V^2/R", R"({"name": "V", "value": 10, "u": 0.5},
                                 {"name": "R", "value": 4, "u": 0.2})");
    b.gum.second_order = true;
    auto g = EvaluateGum(b);
    REQUIRE(g.ok());
    const double want = second_order(
        {2 * v / r, -v * v / (r * r)},
        {{2 / r, -2 * v / (r * r)}, {-2 * v / (r * r), 2 * v * v / (r * r * r)}},
        {{0.0, 4 * v / (r * r * r)}, {-2 / (r * r), -6 * v * v / (r * r * r * r)}}, {uv, ur});
    CHECK(g.value().u == Approx(want).epsilon(1e-12));
  }
  {
    // L sin(theta) at theta = 89.9 deg (in rad): the first-order term nearly vanishes.
    const double len = 2.0, th = 89.9 * M_PI / 180.0, ul = 0.01, ut = 0.02;
    Budget b = Model("L*sin(th)", fmt::format(R"({{"name": "L", "value": 2, "u": 0.01}},
                                                 {{"name": "th", "value": {:.17g}, "u": 0.02}})",
                                              th));
    b.gum.second_order = true;
    auto g = EvaluateGum(b);
    REQUIRE(g.ok());
    const double s = std::sin(th), c = std::cos(th);
    const double want = second_order({s, len * c}, {{0.0, c}, {c, -len * s}},
                                     {{0.0, -s}, {0.0, -len * c}}, {ul, ut});
    CHECK(g.value().u == Approx(want).epsilon(1e-12));
  }
}

TEST_CASE("Logarithms and _pi are read as muparser reads them, with exact derivatives",
          "[uncertainty][gum][derivatives]") {
  // muparser's ln, log10 and _pi are read alike by GiNaC.
  auto logs = EvaluateGum(Model("ln(a) + log10(b) + _pi", R"({"name": "a", "value": 2, "u": 0.1},
                                                               {"name": "b", "value": 100, "u": 1})"));
  REQUIRE(logs.ok());
  CHECK(logs.value().derivatives == "exact (symbolic, GiNaC)");
  for (const BudgetLine& line : logs.value().budget) {
    CHECK(line.sensitivity ==
          Approx(line.name == "a" ? 0.5 : 1.0 / (100.0 * std::log(10.0))).epsilon(1e-14));
  }
  // log10 and log2 inside powers and quotients keep muparser's precedence:
  // y = a^log10(b) / log2(b): at a = 2, b = 100, dy/da = 2 * 2 / log2(100) and
  // dy/db = [4 ln 2 / (100 ln 10)] / log2(100) - 4 / log2(100)^2 / (100 ln 2).
  auto prec = EvaluateGum(Model("a^log10(b) / log2(b)", R"({"name": "a", "value": 2, "u": 0.1},
                                                          {"name": "b", "value": 100, "u": 1})"));
  REQUIRE(prec.ok());
  CHECK(prec.value().derivatives == "exact (symbolic, GiNaC)");
  const double l2 = std::log2(100.0);
  CHECK(prec.value().value == Approx(4.0 / l2).epsilon(1e-14));
  for (const BudgetLine& line : prec.value().budget) {
    const double want = line.name == "a" ? 4.0 / l2
                                         : 4.0 * std::log(2.0) / (100.0 * std::log(10.0)) / l2 -
                                               4.0 / (l2 * l2) / (100.0 * std::log(2.0));
    CHECK(line.sensitivity == Approx(want).epsilon(1e-13));
  }
}

// |a - b| in units of the last place of b.
double Ulps(double a, double b) { return std::fabs(a - b) / (std::nextafter(b, 2 * b) - b); }

TEST_CASE("pi in a model is differentiated exactly (issue #36)",
          "[uncertainty][gum][derivatives]") {
  // y = 2 pi f at f = 1e7 Hz, u(f) = 1 uHz: c = 2 pi, u_c = 2 pi 1e-6 Hz. Central
  // differences at a step of 1e-9 Hz (1e-16 of f) gave u_c 78 % high.
  auto g = EvaluateGum(Model("2*pi*f", R"({"name": "f", "value": 1e7, "u": 1e-6})"));
  REQUIRE(g.ok());
  CHECK(g.value().derivatives == "exact (symbolic, GiNaC)");
  CHECK(g.value().derivatives_exact);
  CHECK(g.value().warnings.empty());
  CHECK(g.value().budget[0].sensitivity == 2.0 * M_PI);  // 2 pi rounded once
  CHECK(Ulps(g.value().u, 2.0 * M_PI * 1e-6) <= 1.0);
  // A phase in degrees through pi/180, as the unit check tells users to write it:
  // y = f cos(phi pi/180), f = 1 GHz +- 1 mHz, phi = 5 deg +- 1e-9 deg.
  const double f = 1e9, uf = 1e-3, phi = 5.0, uphi = 1e-9, rad = M_PI / 180.0;
  auto c = EvaluateGum(Model("f*cos(phi*pi/180)", R"({"name": "f", "value": 1e9, "u": 1e-3},
                                                     {"name": "phi", "value": 5, "u": 1e-9})"));
  REQUIRE(c.ok());
  CHECK(c.value().derivatives == "exact (symbolic, GiNaC)");
  double cf = 0.0, cphi = 0.0;
  for (const BudgetLine& line : c.value().budget) (line.name == "f" ? cf : cphi) = line.sensitivity;
  CHECK(cf == Approx(std::cos(phi * rad)).epsilon(1e-15));
  CHECK(cphi == Approx(-f * std::sin(phi * rad) * rad).epsilon(1e-15));
  CHECK(c.value().u ==
        Approx(std::hypot(std::cos(phi * rad) * uf, f * std::sin(phi * rad) * rad * uphi))
            .epsilon(1e-15));
  // The unit check's advice for an angle in deg ("multiply by pi/180") gives exact
  // derivatives: y = sin(th pi/180), th = 30 deg +- 0.1 deg.
  const Budget advised = Parse(R"json({"measurand": {"name": "y", "unit": "1",
                                                     "model": "sin(th*pi/180)"},
                                       "inputs": [{"name": "th", "value": 30, "u": 0.1,
                                                   "unit": "deg"}],
                                       "monte_carlo": false})json");
  auto s = EvaluateGum(advised);
  REQUIRE(s.ok());
  CHECK(s.value().derivatives == "exact (symbolic, GiNaC)");
  CHECK(s.value().budget[0].sensitivity == Approx(std::cos(M_PI / 6.0) * rad).epsilon(1e-15));
}

// One input a (and b) at the given values; the sensitivities against closed forms.
struct DerivativeCase {
  const char* model;
  double a, b;
  double dyda, dydb;
};

TEST_CASE("Every constant and function of the model grammar is differentiated exactly",
          "[uncertainty][gum][derivatives]") {
  const double a = 0.3, b = 1.7;
  const double e = std::exp(1.0);
  const std::vector<DerivativeCase> cases = {
      {"pi*a + b", a, b, M_PI, 1.0},
      {"_pi*a + b", a, b, M_PI, 1.0},
      {"_e^a + b", a, b, std::pow(e, a) * std::log(e), 1.0},
      {"sin(a) + b", a, b, std::cos(a), 1.0},
      {"cos(a) + b", a, b, -std::sin(a), 1.0},
      {"tan(a) + b", a, b, 1.0 / (std::cos(a) * std::cos(a)), 1.0},
      {"asin(a) + b", a, b, 1.0 / std::sqrt(1.0 - a * a), 1.0},
      {"acos(a) + b", a, b, -1.0 / std::sqrt(1.0 - a * a), 1.0},
      {"atan(a) + b", a, b, 1.0 / (1.0 + a * a), 1.0},
      {"sinh(a) + b", a, b, std::cosh(a), 1.0},
      {"cosh(a) + b", a, b, std::sinh(a), 1.0},
      {"tanh(a) + b", a, b, 1.0 / (std::cosh(a) * std::cosh(a)), 1.0},
      {"asinh(a) + b", a, b, 1.0 / std::sqrt(a * a + 1.0), 1.0},
      {"acosh(b) + a", a, b, 1.0, 1.0 / std::sqrt(b * b - 1.0)},
      {"atanh(a) + b", a, b, 1.0 / (1.0 - a * a), 1.0},
      {"exp(a) + b", a, b, std::exp(a), 1.0},
      {"sqrt(a) + b", a, b, 0.5 / std::sqrt(a), 1.0},
      {"log(a) + b", a, b, 1.0 / a, 1.0},
      {"ln(a) + b", a, b, 1.0 / a, 1.0},
      {"log10(a) + b", a, b, 1.0 / (a * std::log(10.0)), 1.0},
      {"log2(a) + b", a, b, 1.0 / (a * std::log(2.0)), 1.0},
      {"atan2(a, b)", a, b, b / (a * a + b * b), -a / (a * a + b * b)},
      {"a^b", a, b, b * std::pow(a, b - 1.0), std::pow(a, b) * std::log(a)},
      {"a^b^2", a, b, b * b * std::pow(a, b * b - 1.0), std::pow(a, b * b) * std::log(a) * 2 * b},
      {"-a^2 + b", a, b, -2.0 * a, 1.0},
      {"a*1e-3 + 0.1*b", a, b, 1e-3, 0.1},
      {"sum(a, b, 2)", a, b, 1.0, 1.0},
      {"avg(a, b, 2)", a, b, 1.0 / 3.0, 1.0 / 3.0},
      // Piecewise: the piece that holds at the estimates.
      {"abs(a - b)", a, b, -1.0, 1.0},
      {"sign(a - b) * a + b", a, b, -1.0, 1.0},
      {"rint(b) + a*b", a, b, b, a},
      {"min(a, b)", a, b, 1.0, 0.0},
      {"max(a, b, 1)", a, b, 0.0, 1.0},
      {"(a < b) * b + a", a, b, 1.0, 1.0},
      {"(a >= b) * b + a", a, b, 1.0, 0.0},
      {"a > b ? a : b*b", a, b, 0.0, 2.0 * b},
      {"(a > 0 && b < 1) ? a : b", a, b, 0.0, 1.0},
      {"(a > 0 || b < 1) ? a : b", a, b, 1.0, 0.0},
  };
  for (const DerivativeCase& k : cases) {
    INFO(k.model);
    auto g = EvaluateGum(Model(k.model, fmt::format(R"({{"name": "a", "value": {}, "u": 0.01}},
                                                       {{"name": "b", "value": {}, "u": 0.01}})",
                                                    k.a, k.b)));
    REQUIRE(g.ok());
    CHECK(g.value().derivatives == "exact (symbolic, GiNaC)");
    for (const BudgetLine& line : g.value().budget) {
      INFO(line.name);
      const double want = line.name == "a" ? k.dyda : k.dydb;
      CHECK(line.sensitivity == Approx(want).epsilon(1e-14).margin(1e-300));
    }
  }
}

TEST_CASE("A model without a derivative at the estimates is never silent",
          "[uncertainty][gum][derivatives]") {
  // abs at 0, a tie of min: central differences, named in the warning with each input's
  // relative step; with monte_carlo disabled the budget is refused.
  for (const char* model : {"abs(a - b) + a", "min(a, b) + a"}) {
    INFO(model);
    const Budget b = Model(model, R"({"name": "a", "value": 2, "u": 0.1},
                                     {"name": "b", "value": 2, "u": 0.1})");
    auto g = EvaluateGum(b);
    REQUIRE(g.ok());
    CHECK_FALSE(g.value().derivatives_exact);
    CHECK(g.value().derivatives.rfind("central differences: column 1: ", 0) == 0);
    CHECK(g.value().derivatives.find("seam") != std::string::npos);
    REQUIRE(g.value().warnings.size() == 1);
    const std::string& w = g.value().warnings[0];
    // h = 1e-3 u = 1e-4 at x = 2: relative step 5e-05.
    CHECK(w.find("'a' h = 0.0001 (relative step h/|x| = 5e-05)") != std::string::npos);
    CHECK(w.find("'b' h = 0.0001 (relative step h/|x| = 5e-05)") != std::string::npos);
    CHECK(w.find("the Monte Carlo result is the stated one") != std::string::npos);
    auto refused = EvaluateBudget(b);
    REQUIRE_FALSE(refused.ok());
    CHECK(refused.error().kind == ErrorKind::kInput);
    CHECK(refused.error().message.find("enable monte_carlo") != std::string::npos);
  }
  // With the Monte Carlo method it runs, and the Monte Carlo result is the stated one.
  const Budget mc = Model("abs(a - b) + a", R"({"name": "a", "value": 2, "u": 0.1},
                                               {"name": "b", "value": 2, "u": 0.1})",
                          20000);
  auto e = EvaluateBudget(mc);
  REQUIRE(e.ok());
  const BudgetReport r = MakeBudgetReport(e.value());
  CHECK(r.stated.method == kStatedMonteCarlo);
  CHECK(r.stated.value == r.monte_carlo->value);
  CHECK(r.stated.u == r.monte_carlo->u);
  CHECK(r.stated.interval.low == r.monte_carlo->shortest.low);
  CHECK(r.stated.reason.find("central differences") != std::string::npos);
  // Away from the seam the same model has exact derivatives: d/da (|a - b| + a) = 2.
  auto away = EvaluateGum(Model("abs(a - b) + a", R"({"name": "a", "value": 3, "u": 0.1},
                                                     {"name": "b", "value": 2, "u": 0.1})"));
  REQUIRE(away.ok());
  CHECK(away.value().derivatives_exact);
  CHECK(away.value().u == Approx(std::hypot(0.2, 0.1)).epsilon(1e-15));
}

}  // namespace
}  // namespace metro
