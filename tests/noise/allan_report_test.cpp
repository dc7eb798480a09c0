#include "metro/noise/allan_report.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "metro/noise/noise_units.hpp"
#include "noise/allan_report_json.hpp"
#include "noise/noise_simulation.hpp"

namespace metro {
namespace {

TEST_CASE("Unit table converts to the conventional units", "[noise]") {
  const NoiseUnits dps = NoiseUnitsFor("deg/s");
  CHECK(dps.known);
  const UnitConversion& n = dps.terms[static_cast<int>(NoiseTerm::kRandomWalk)];
  CHECK(n.unit == "deg/s*sqrt(s)");
  CHECK(n.unit_conventional == "deg/sqrt(h)");
  // IEEE Std 952-1997 Annex C units: deg/sqrt(h) = 60 x deg/s/sqrt(Hz).
  CHECK(n.factor == Approx(60.0));
  CHECK(dps.terms[static_cast<int>(NoiseTerm::kBiasInstability)].factor == Approx(3600.0));
  CHECK(dps.terms[static_cast<int>(NoiseTerm::kRateRandomWalk)].factor ==
        Approx(std::pow(3600.0, 1.5)));
  // MPU6050 datasheet: one-sided 0.005 deg/s/sqrt(Hz) -> N = 0.0035 deg/s*sqrt(s)
  // = 0.21 deg/sqrt(h) (IEEE Std 952-1997 Annex C units; docs/noise.md).
  CHECK(0.005 / std::sqrt(2.0) * n.factor == Approx(0.2121).epsilon(1e-3));
  const NoiseUnits rads = NoiseUnitsFor("rad/s");
  CHECK(rads.terms[static_cast<int>(NoiseTerm::kBiasInstability)].factor ==
        Approx(3600.0 * 180.0 / M_PI));
  CHECK(rads.column_token == "rads");
  const NoiseUnits g = NoiseUnitsFor("g");
  CHECK(g.terms[static_cast<int>(NoiseTerm::kBiasInstability)].unit_conventional == "ug");
  CHECK(g.terms[static_cast<int>(NoiseTerm::kBiasInstability)].factor == Approx(1e6));
  CHECK(g.terms[static_cast<int>(NoiseTerm::kRandomWalk)].unit_conventional == "m/s/sqrt(h)");
  CHECK(g.terms[static_cast<int>(NoiseTerm::kRandomWalk)].factor == Approx(9.80665 * 60.0));
  CHECK(g.density.unit_conventional == "ug/sqrt(Hz)");
  const NoiseUnits mps2 = NoiseUnitsFor("m/s^2");
  CHECK(mps2.terms[static_cast<int>(NoiseTerm::kBiasInstability)].factor == Approx(1e6 / 9.80665));
  const NoiseUnits lsb = NoiseUnitsFor("LSB");
  CHECK(lsb.known);
  CHECK(lsb.terms[static_cast<int>(NoiseTerm::kRateRandomWalk)].unit == "LSB/sqrt(s)");
  CHECK(lsb.terms[static_cast<int>(NoiseTerm::kRateRandomWalk)].factor == 1.0);
  const NoiseUnits other = NoiseUnitsFor("furlong/fortnight");
  CHECK_FALSE(other.known);
  CHECK(other.terms[static_cast<int>(NoiseTerm::kQuantization)].unit == "furlong/fortnight*s");
}

TEST_CASE("Allan JSON has the report shape and white noise numbers", "[noise]") {
  // White gyro noise of one-sided density 0.005 deg/s/sqrt(Hz) at 100 Hz: N = 0.005/sqrt2.
  const double density = 0.005, tau0 = 0.01;
  const double n = density / std::sqrt(2.0);
  const std::vector<double> y = testing::WhiteNoise(1 << 18, n / std::sqrt(tau0), 42);
  const Result<AllanCurve> curve = ComputeAllan(y, tau0);
  REQUIRE(curve.ok());
  const Result<NoiseFit> fit = FitNoiseTerms(curve.value());
  REQUIRE(fit.ok());
  const nlohmann::ordered_json j =
      ToJsonValue(MakeAllanReport(curve.value(), fit.value(), "deg/s"));
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  CHECK(keys == std::vector<std::string>{"estimator", "tau_s", "adev", "ci_low", "ci_high", "edf",
                                         "n_terms", "n_terms_gap_free", "missing_fraction",
                                         "confidence", "alpha", "alpha_source", "noise",
                                         "sample_period", "model_check"});
  // White noise is what the model describes: it holds over the whole curve (issue #36).
  CHECK(j["model_check"]["tested"] == true);
  CHECK(j["model_check"]["rejected"] == false);
  // The level of the intervals and the noise type behind each one (white rate: alpha 0).
  CHECK(j["confidence"].get<double>() == Approx(0.683));
  REQUIRE(j["alpha"].size() == curve.value().size());
  CHECK(j["alpha"][0] == 0);
  CHECK(j["alpha"][3] == 0);
  CHECK(j["alpha_source"][0] == "lag1_acf");
  CHECK(j["alpha_source"].back() == "carried");  // a handful of averages at the longest tau
  // A record without gaps: every term is there.
  CHECK(j["n_terms_gap_free"] == j["n_terms"]);
  for (const auto& f : j["missing_fraction"]) CHECK(f.get<double>() == 0.0);
  CHECK(j["estimator"] == "oadev");
  CHECK(j["tau_s"].size() == curve.value().size());
  CHECK(j["tau_s"][0].get<double>() == Approx(0.01));
  const auto& rw = j["noise"]["random_walk"];
  CHECK(rw["supported"] == true);
  CHECK(rw["unit"] == "deg/s*sqrt(s)");
  CHECK(rw["unit_conventional"] == "deg/sqrt(h)");
  CHECK(rw["value"].get<double>() == Approx(n).epsilon(0.01));
  CHECK(rw["value_conventional"].get<double>() == Approx(n * 60).epsilon(0.01));
  CHECK(rw["density_one_sided"].get<double>() == Approx(density).epsilon(0.01));
  CHECK(rw["unit_density"] == "deg/s/sqrt(Hz)");
  CHECK(rw["readoff"]["tau_s"].get<double>() == Approx(1.0));
  for (const char* key :
       {"quantization", "random_walk", "bias_instability", "rate_random_walk", "rate_ramp"}) {
    INFO(key);
    REQUIRE(j["noise"].contains(key));
    for (const char* field : {"value", "u", "unit", "value_conventional", "unit_conventional"}) {
      CHECK(j["noise"][key].contains(field));
    }
  }
  CHECK(j["noise"]["bias_instability"]["value"].is_null());
  CHECK(j["noise"]["bias_instability"]["unit_conventional"] == "deg/h");

  const nlohmann::ordered_json link =
      ToJsonValue(MakeAllanTypeALink(curve.value(), fit.value(), 100.0));
  CHECK(link["u_mean_allan"].get<double>() == Approx(n / 10.0).epsilon(0.01));
  CHECK(link["dominant_term"] == "random_walk");
  CHECK(link["allan_min_at_end"] == true);  // White noise: averaging helps to the end.
}

TEST_CASE("Allan CSV carries units in the header and blanks for NaN", "[noise]") {
  AllanCurve c;
  c.estimator = AllanEstimator::kOhdev;
  c.m = {1, 2};
  c.tau_s = {0.01, 0.02};
  c.dev = {0.5, 0.25};
  c.ci_low = {0.4, std::nan("")};
  c.ci_high = {0.6, std::nan("")};
  c.edf = {12.5, std::nan("")};
  c.n_terms = {97, 94};
  c.n_terms_gap_free = {97, 100};  // 6 of the 100 terms at m = 2 read a missing sample
  c.alpha = {0, 0};
  c.alpha_source = {AlphaSource::kLag1Acf, AlphaSource::kCarried};
  CHECK(AllanCurveCsv(c, "deg/s") ==
        "tau_s,m,n_terms,alpha,alpha_source,edf,ohdev_dps,ci_low_dps,ci_high_dps,"
        "missing_fraction\n"
        "0.01,1,97,0,lag1_acf,12.5,0.5,0.4,0.6,0\n"
        "0.02,2,94,0,carried,,0.25,,,0.06\n");
}

}  // namespace
}  // namespace metro
