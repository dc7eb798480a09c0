// Writes a long six-channel IMU record for the streaming benchmark (issue #38 step 5):
// t_s at `rate` Hz (4 decimals), ax_g..az_g and gx_dps..gz_dps, each white noise plus a
// random-walk bias (accelerometer 150 ug/sqrt(Hz) about (0, 0, 1) g, gyroscope
// 0.005 deg/s/sqrt(Hz) about 0.2 deg/s), 7 significant digits.
//   metro_bench_noise_gen_day OUT.csv [HOURS=24] [RATE_HZ=400] [SEED=1]
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT.csv [HOURS] [RATE_HZ] [SEED]\n", argv[0]);
    return 2;
  }
  const double hours = argc > 2 ? std::atof(argv[2]) : 24.0;
  const double rate_hz = argc > 3 ? std::atof(argv[3]) : 400.0;
  const unsigned long long seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1ULL;
  const long long n = std::llround(hours * 3600.0 * rate_hz);
  const double white_g = 150e-6 * std::sqrt(rate_hz);
  const double white_dps = 0.005 * std::sqrt(rate_hz);
  const double walk_g = 1e-6 / std::sqrt(rate_hz);
  const double walk_dps = 1e-4 / std::sqrt(rate_hz);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::FILE* out = std::fopen(argv[1], "wb");
  if (out == nullptr) {
    std::perror(argv[1]);
    return 1;
  }
  fmt::memory_buffer buf;
  fmt::format_to(std::back_inserter(buf), "t_s,ax_g,ay_g,az_g,gx_dps,gy_dps,gz_dps\n");
  double bias[6] = {0.0, 0.0, 1.0, 0.2, 0.2, 0.2};
  for (long long i = 0; i < n; ++i) {
    fmt::format_to(std::back_inserter(buf), "{:.4f}", static_cast<double>(i) / rate_hz);
    for (int c = 0; c < 6; ++c) {
      bias[c] += (c < 3 ? walk_g : walk_dps) * normal(rng);
      fmt::format_to(std::back_inserter(buf), ",{:.7g}",
                     bias[c] + (c < 3 ? white_g : white_dps) * normal(rng));
    }
    buf.push_back('\n');
    if (buf.size() > (1 << 20)) {
      std::fwrite(buf.data(), 1, buf.size(), out);
      buf.clear();
    }
  }
  std::fwrite(buf.data(), 1, buf.size(), out);
  return std::fclose(out) == 0 ? 0 : 1;
}
