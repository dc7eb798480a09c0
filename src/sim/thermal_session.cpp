// SimulateThermalSession: draw the truth, walk the temperature profile, sample the counts,
// inject the temperature read errors, assemble the session (thermal_session.hpp).
#include "metro/sim/thermal_session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <pcg_random.hpp>
#include <random>

#include "metro/io/columns.hpp"

namespace metro {

const char* ThermalProfileName(ThermalProfile profile) {
  switch (profile) {
    case ThermalProfile::kRamp:
      return "ramp";
    case ThermalProfile::kSteps:
      return "steps";
    case ThermalProfile::kWarmup:
      return "warmup";
  }
  return "?";
}

bool ThermalSimulationOptions::IsValid(std::string* why) const {
  auto fail = [&](std::string text) {
    if (why) *why = std::move(text);
    return false;
  };
  if (!(rate_hz > 0 && rate_hz <= 1000)) return fail("rate_hz must be in (0, 1000]");
  if (!(temp_high_c > temp_low_c)) return fail("temp_high_c must exceed temp_low_c");
  if (temp_low_c < -40 || temp_high_c > 85) {
    return fail("the temperatures must lie in the MPU6050's operating range -40 .. 85 degC");
  }
  if (bias_order < 1 || bias_order > 4) return fail("bias_order must be 1 .. 4");
  if (profile == ThermalProfile::kSteps && steps < 2) return fail("steps must be >= 2");
  if (!(ramp_s > 0 && step_dwell_s > 0 && step_tau_s > 0 && warmup_tau_s > 0 && warmup_s > 0)) {
    return fail("durations and time constants must be positive");
  }
  if (profile == ThermalProfile::kWarmup && cooling_leg) {
    return fail("a warm-up has no cooling leg (use --thermal-profile ramp or steps)");
  }
  if (!cooling_leg && (accel_hysteresis_g != 0 || gyro_hysteresis_dps != 0)) {
    return fail("hysteresis needs a cooling leg (--cooling-leg)");
  }
  if (temp_glitches < 0) return fail("temp_glitches must be >= 0");
  if (!(accel_noise_ug_rthz >= 0 && gyro_noise_dps_rthz >= 0 && bandwidth_hz > 0)) {
    return fail("noise densities must be >= 0 and the bandwidth > 0");
  }
  return true;
}

double ThermalSensorTruth::BiasAt(int axis, double temp_c, double t_ref_c, int leg) const {
  const Eigen::VectorXd& c = coefficients[axis];
  const double x = temp_c - t_ref_c;
  double b = 0;
  for (int j = static_cast<int>(c.size()) - 1; j >= 0; --j) b = b * x + c[j];  // Horner.
  return b + 0.5 * leg * hysteresis_lsb[axis];
}

namespace {

constexpr double kAccelLsbPerG = 16384.0;  // PS-MPU-6000A-00 rev 3.4, +-2 g.
constexpr double kGyroLsbPerDps = 131.0;   // +-250 deg/s.

double Uniform(pcg64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

ThermalSensorTruth DrawSensorTruth(pcg64& rng, int order, double half_span_c, double lsb_per_unit,
                                   double b0_half_width, double excursion, double hysteresis) {
  ThermalSensorTruth s;
  s.lsb_per_unit = lsb_per_unit;
  for (int a = 0; a < 3; ++a) {
    Eigen::VectorXd c(order + 1);
    c[0] = Uniform(rng, -b0_half_width, b0_half_width) * lsb_per_unit;
    for (int j = 1; j <= order; ++j) {
      const double sign = Uniform(rng, -1, 1) < 0 ? -1.0 : 1.0;
      const double magnitude = Uniform(rng, 0.3, 1.0) * excursion / order * lsb_per_unit;
      c[j] = sign * magnitude / std::pow(half_span_c, j);  // x^j of x / half_span -> degC^-j
    }
    s.coefficients[a] = c;
    s.hysteresis_lsb[a] = hysteresis * lsb_per_unit;
  }
  return s;
}

// The total duration of the profile [s].
double ProfileDuration(const ThermalSimulationOptions& o) {
  const double legs = o.cooling_leg ? 2.0 : 1.0;
  switch (o.profile) {
    case ThermalProfile::kRamp:
      return legs * o.ramp_s;
    case ThermalProfile::kSteps:
      return legs * o.steps * o.step_dwell_s;
    case ThermalProfile::kWarmup:
      return o.warmup_s;
  }
  return 0;
}

// The heating leg's temperature at s seconds into it (0 <= s <= one leg's duration).
double HeatingLeg(const ThermalSimulationOptions& o, double s) {
  const double lo = o.temp_low_c, span = o.temp_high_c - o.temp_low_c;
  switch (o.profile) {
    case ThermalProfile::kRamp:
      return lo + span * std::min(1.0, s / o.ramp_s);
    case ThermalProfile::kWarmup:
      return lo + span * (1.0 - std::exp(-s / o.warmup_tau_s));
    case ThermalProfile::kSteps: {
      // First-order response to a staircase: level i from i * dwell, starting at level 0.
      const int i = std::min(o.steps - 1, static_cast<int>(std::floor(s / o.step_dwell_s)));
      const double step_c = span / (o.steps - 1);
      double temp = lo;
      for (int k = 1; k <= i; ++k) {
        temp += step_c * (1.0 - std::exp(-(s - k * o.step_dwell_s) / o.step_tau_s));
      }
      return temp;
    }
  }
  return lo;
}

// temp_c(t) and the leg (+1 heating, -1 cooling): the cooling leg mirrors the heating one.
std::pair<double, int> Profile(const ThermalSimulationOptions& o, double t) {
  const double leg_s = o.cooling_leg ? 0.5 * ProfileDuration(o) : ProfileDuration(o);
  if (t <= leg_s) return {HeatingLeg(o, t), 1};
  return {o.temp_low_c + o.temp_high_c - HeatingLeg(o, t - leg_s), -1};
}

void AddColumns(const ThermalSimulationOptions& o, Tag tag,
                std::array<std::vector<double>, 7>* cols, Session* s) {
  const char* names[7] = {"ax_lsb", "ay_lsb", "az_lsb", "gx_lsb", "gy_lsb", "gz_lsb", "temp_c"};
  s->path = fmt::format("simulated-thermal-seed-{}", o.seed);
  s->format = SessionFormat::kCsv;
  s->rows = static_cast<int64_t>(tag.t_s.size());
  s->columns = {"t_s", "sensor"};
  for (int c = 0; c < 7; ++c) {
    Quantity q;
    q.name = names[c];
    q.unit = ClassifyColumn(names[c]).UnitSymbol();
    q.values = std::move((*cols)[c]);
    tag.quantities.push_back(std::move(q));
    s->columns.push_back(names[c]);
  }
  s->tags.push_back(std::move(tag));
}

// The samples: counts through the truth's bias at the true temperature, the temperature
// read at 1/340 degC.
void Sample(const ThermalSimulationOptions& o, pcg64& rng, SimulatedThermalSession* out,
            std::array<std::vector<double>, 7>* cols, Tag* tag) {
  const size_t n = static_cast<size_t>(std::floor(ProfileDuration(o) * o.rate_hz)) + 1;
  const double accel_sd_lsb =
      o.accel_noise_ug_rthz * 1e-6 * std::sqrt(o.bandwidth_hz) * kAccelLsbPerG;
  const double gyro_sd_lsb = o.gyro_noise_dps_rthz * std::sqrt(o.bandwidth_hz) * kGyroLsbPerDps;
  const double truth_lsb[6] = {0, 0, kAccelLsbPerG, 0, 0, 0};  // At rest, +z up.
  std::normal_distribution<double> normal(0.0, 1.0);
  const ThermalTruth& tr = out->truth;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / o.rate_hz;
    const auto [temp_c, leg] = Profile(o, t);
    for (int c = 0; c < 6; ++c) {
      const ThermalSensorTruth& s = c < 3 ? tr.accel : tr.gyro;
      const double sd = c < 3 ? accel_sd_lsb : gyro_sd_lsb;
      const double raw = truth_lsb[c] + s.BiasAt(c % 3, temp_c, tr.t_ref_c, leg) + sd * normal(rng);
      (*cols)[c].push_back(std::clamp(std::round(raw), -32768.0, 32767.0));
    }
    (*cols)[6].push_back(std::round(temp_c * 340.0) / 340.0);  // MPU6050: 340 LSB/degC.
    out->true_temp_c.push_back(temp_c);
    out->leg.push_back(leg);
    tag->t_s.push_back(t);
    tag->line.push_back(static_cast<uint32_t>(k + 2));
  }
}

}  // namespace

Result<SimulatedThermalSession> SimulateThermalSession(const ThermalSimulationOptions& o) {
  std::string why;
  if (!o.IsValid(&why)) return MakeError("invalid thermal simulation options: " + why);
  SimulatedThermalSession out;
  pcg64 rng(o.seed ^ 0x7f4a7c159e3779b9ULL);
  ThermalTruth& tr = out.truth;
  tr.order = o.bias_order;
  tr.t_ref_c = 0.5 * (o.temp_low_c + o.temp_high_c);
  const double half_span = 0.5 * (o.temp_high_c - o.temp_low_c);
  tr.accel = DrawSensorTruth(rng, o.bias_order, half_span, kAccelLsbPerG, 0.050,
                             o.accel_excursion_g, o.accel_hysteresis_g);
  tr.gyro = DrawSensorTruth(rng, o.bias_order, half_span, kGyroLsbPerDps, 20.0,
                            o.gyro_excursion_dps, o.gyro_hysteresis_dps);
  std::array<std::vector<double>, 7> cols;
  Tag tag;
  tag.sensor = o.sensor;
  Sample(o, rng, &out, &cols, &tag);
  // Read errors: isolated rows away from the ends, distinct.
  std::uniform_int_distribution<size_t> row(1, cols[6].size() - 2);
  for (int g = 0; g < o.temp_glitches; ++g) {
    const size_t r = row(rng);
    if (std::count(tr.glitch_lines.begin(), tr.glitch_lines.end(), tag.line[r]) > 0) continue;
    cols[6][r] += o.temp_glitch_c;
    tr.glitch_lines.push_back(tag.line[r]);
  }
  std::sort(tr.glitch_lines.begin(), tr.glitch_lines.end());
  AddColumns(o, std::move(tag), &cols, &out.session);
  return out;
}

namespace {

nlohmann::ordered_json SensorJson(const ThermalSensorTruth& s, const char* unit) {
  nlohmann::ordered_json axes = nlohmann::ordered_json::array();
  for (int a = 0; a < 3; ++a) {
    const Eigen::VectorXd& c = s.coefficients[a];
    axes.push_back(std::vector<double>(c.data(), c.data() + c.size()));
  }
  return {{"input_unit", "LSB"},
          {"lsb_per_unit", s.lsb_per_unit},
          {"unit", unit},
          {"bias_coefficients_lsb_per_c_pow_j", axes},
          {"hysteresis_lsb", {s.hysteresis_lsb[0], s.hysteresis_lsb[1], s.hysteresis_lsb[2]}}};
}

}  // namespace

std::string ThermalTruthJson(const ThermalSimulationOptions& o,
                             const SimulatedThermalSession& sim) {
  using Json = nlohmann::ordered_json;
  const ThermalTruth& tr = sim.truth;
  Json j = {{"schema", "metro.thermal-truth/1"},
            {"model_equation",
             "raw = M^-1 truth + b0 + sum_j c_j (temp_c - t_ref_c)^j + leg h / 2, leg +1 "
             "heating, -1 cooling (docs/thermal.md)"},
            {"seed", o.seed},
            {"sensor", o.sensor},
            {"rate_hz", o.rate_hz},
            {"profile", ThermalProfileName(o.profile)},
            {"temp_low_c", o.temp_low_c},
            {"temp_high_c", o.temp_high_c},
            {"cooling_leg", o.cooling_leg},
            {"bias_order", tr.order},
            {"t_ref_c", tr.t_ref_c},
            {"accel_noise_ug_rthz", o.accel_noise_ug_rthz},
            {"gyro_noise_dps_rthz", o.gyro_noise_dps_rthz},
            {"bandwidth_hz", o.bandwidth_hz},
            {"rows", sim.session.rows},
            {"temp_glitch_lines", tr.glitch_lines}};
  j["accel"] = SensorJson(tr.accel, "g");
  j["gyro"] = SensorJson(tr.gyro, "deg/s");
  return j.dump(2) + "\n";
}

}  // namespace metro
