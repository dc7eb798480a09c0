#include "metro/noise/sample_period.hpp"

#include <catch2/catch.hpp>
#include <cmath>

namespace metro {
namespace {

// t_i = i * 0.1 s (+ jitter), lines 2, 3, ... (a header on line 1).
void Uniform(size_t n, std::vector<double>* t, std::vector<uint32_t>* line) {
  t->clear();
  line->clear();
  for (size_t i = 0; i < n; ++i) {
    t->push_back(0.1 * static_cast<double>(i) + 5.0);
    line->push_back(static_cast<uint32_t>(i + 2));
  }
}

TEST_CASE("Sample period, jitter and gaps from timestamps", "[noise]") {
  std::vector<double> t;
  std::vector<uint32_t> line;
  Uniform(1000, &t, &line);
  // Intervals cycle 0.100, 0.101, 0.099 s: median 0.1 s, RMS jitter sqrt(2/3) ms, max 1 ms.
  const double kCycle[3] = {0.0, 0.001, -0.001};
  for (size_t i = 1; i < t.size(); ++i) t[i] = t[i - 1] + 0.1 + kCycle[i % 3];
  const Result<SamplePeriod> p = EstimateSamplePeriod(t, line);
  REQUIRE(p.ok());
  CHECK(p.value().tau0_s == Approx(0.1).epsilon(1e-9));
  CHECK(p.value().rate_hz == Approx(10.0).epsilon(1e-9));
  CHECK(p.value().jitter_rms_s == Approx(0.001 * std::sqrt(2.0 / 3.0)).epsilon(1e-6));
  CHECK(p.value().max_abs_jitter_s == Approx(0.001).epsilon(1e-6));
  CHECK(p.value().gaps.empty());

  // Remove samples 100..102 (lines 102..104): one gap of 0.4 s, 3 samples missing, at line 105.
  t.erase(t.begin() + 100, t.begin() + 103);
  line.erase(line.begin() + 100, line.begin() + 103);
  const Result<SamplePeriod> refused = EstimateSamplePeriod(t, line);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().line == 105);
  CHECK(refused.error().ToString() ==
        "line 105: 1 gap longer than 1.5 x the median interval 0.1 s at line 105 (3 samples "
        "missing): the Allan estimators need uniform sampling; analyse the runs between gaps "
        "separately");
  SamplePeriodOptions allow;
  allow.allow_gaps = true;
  const Result<SamplePeriod> warned = EstimateSamplePeriod(t, line, allow);
  REQUIRE(warned.ok());
  REQUIRE(warned.value().gaps.size() == 1);
  CHECK(warned.value().gaps[0].line == 105);
  CHECK(warned.value().gaps[0].missing_samples == 3);
  CHECK(warned.value().missing_samples == 3);
  CHECK(warned.value().warnings[0].rfind("line 105: gap of 0.4", 0) == 0);
}

TEST_CASE("Sample period of corrupt huge gaps saturates its counts", "[noise]") {
  // 21 samples 1 s apart, then three 1e300 s jumps (a corrupt clock): the missing-sample
  // count of each gap (1e300) and their sum saturate at 1e18 instead of overflowing int64
  // (UBSan, issue #20).
  std::vector<double> t;
  std::vector<uint32_t> line;
  for (int i = 0; i <= 20; ++i) t.push_back(i);
  for (double v : {1e300, 2e300, 3e300}) t.push_back(v);
  for (size_t i = 0; i < t.size(); ++i) line.push_back(static_cast<uint32_t>(i + 2));
  SamplePeriodOptions allow;
  allow.allow_gaps = true;
  const Result<SamplePeriod> p = EstimateSamplePeriod(t, line, allow);
  REQUIRE(p.ok());
  CHECK(p.value().tau0_s == 1.0);
  REQUIRE(p.value().gaps.size() == 3);
  CHECK(p.value().gaps[0].missing_samples == 1000000000000000000);
  CHECK(p.value().missing_samples == 1000000000000000000);
}

TEST_CASE("Sample period refuses resets, bad sizes and heavy jitter", "[noise]") {
  std::vector<double> t;
  std::vector<uint32_t> line;
  Uniform(50, &t, &line);
  SECTION("reset") {
    t[20] = t[19];  // line 22: time stands still
    t[30] = 0.0;    // line 32: time runs back
    const Result<SamplePeriod> r = EstimateSamplePeriod(t, line);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().ToString() ==
          "line 22: time does not increase at lines 22, 32 (2 resets): the Allan estimators need "
          "one uniformly sampled run; split the log there");
  }
  SECTION("non-finite") {
    t[7] = std::nan("");
    CHECK(EstimateSamplePeriod(t, line).error().ToString() ==
          "line 9: timestamp nan is not finite");
  }
  SECTION("sizes") {
    line.pop_back();
    CHECK(EstimateSamplePeriod(t, line).error().message ==
          "sample period: 50 timestamps but 49 line numbers");
  }
  SECTION("too few") {
    CHECK(EstimateSamplePeriod({0.0, 1.0}, {1, 2}).error().message ==
          "sample period: 2 timestamps are too few (at least 3 are needed)");
  }
  SECTION("jitter") {
    for (size_t i = 1; i < t.size(); i += 2) t[i] += 0.02;  // +-20 ms on 100 ms
    const Result<SamplePeriod> r = EstimateSamplePeriod(t, line);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.rfind("sample period: RMS jitter 0.02", 0) == 0);
  }
  SECTION("options") {
    SamplePeriodOptions bad;
    bad.gap_factor = 1.0;
    CHECK(EstimateSamplePeriod(t, line, bad).error().message ==
          "sample period options: gap_factor 1 must be a number above 1");
  }
}

TEST_CASE("A drifting sample interval is warned with its range", "[noise]") {
  // 10001 samples whose interval drifts linearly from 9 ms to 12 ms (audit of issue #22): the
  // tenths' medians run from 9.15 ms to 11.85 ms (the middle of each tenth), 27 % of tau0.
  std::vector<double> t = {0.0};
  std::vector<uint32_t> line = {2};
  for (size_t i = 0; i < 10000; ++i) {
    t.push_back(t.back() + 0.009 + 0.003 * (static_cast<double>(i) + 0.5) / 10000.0);
    line.push_back(static_cast<uint32_t>(i + 3));
  }
  const Result<SamplePeriod> p = EstimateSamplePeriod(t, line);
  REQUIRE(p.ok());
  CHECK(p.value().drift_first_dt_s == Approx(0.00915).epsilon(1e-3));
  CHECK(p.value().drift_last_dt_s == Approx(0.01185).epsilon(1e-3));
  CHECK(p.value().drift_min_dt_s == Approx(0.00915).epsilon(1e-3));
  CHECK(p.value().drift_max_dt_s == Approx(0.01185).epsilon(1e-3));
  REQUIRE(p.value().warnings.size() == 1);
  CHECK(p.value().warnings[0] ==
        "sample interval drifts: the median interval of tenths of the record ranges from "
        "0.00915015 s to 0.0118502 s (0.00915015 s in the first tenth, lines 2-1002, 0.0118502 s "
        "in the last, lines 9002-10002); the Allan taus assume one tau0 = 0.0105 s");

  // A steady clock with jitter of +-1 % and a 0.5 % drift stays quiet.
  std::vector<double> t2 = {0.0};
  const double kCycle[3] = {0.0, 0.0001, -0.0001};
  for (size_t i = 0; i < 10000; ++i) {
    t2.push_back(t2.back() + 0.01 * (1.0 + 0.005 * static_cast<double>(i) / 10000.0) +
                 kCycle[i % 3]);
  }
  const Result<SamplePeriod> q = EstimateSamplePeriod(t2, line);
  REQUIRE(q.ok());
  CHECK(q.value().warnings.empty());
  CHECK(q.value().drift_max_dt_s - q.value().drift_min_dt_s < 0.0001);
  SamplePeriodOptions o;
  o.max_relative_drift = 0.0;
  std::string why;
  CHECK_FALSE(o.IsValid(&why));
  CHECK(why == "max_relative_drift 0 must be above 0");
}

}  // namespace
}  // namespace metro
