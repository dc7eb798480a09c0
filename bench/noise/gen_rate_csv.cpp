// Writes a one-column CSV of simulated gyro rate samples (deg/s) for the OADEV benchmark:
// white noise N = 0.0035 deg/s*sqrt(s) at 100 Hz plus a random-walk bias, 7 significant
// digits per value (about 11 bytes per line), header "gx_dps".
//   metro_bench_noise_gen OUT.csv [N_SAMPLES=10000000] [SEED=1]
#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT.csv [N_SAMPLES] [SEED]\n", argv[0]);
    return 2;
  }
  const long long n = argc > 2 ? std::atoll(argv[2]) : 10000000LL;
  const unsigned long long seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1ULL;
  const double tau0_s = 0.01;
  const double white_dps = 0.0035 / std::sqrt(tau0_s);
  const double walk_step_dps = 1e-4 * std::sqrt(tau0_s);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::FILE* out = std::fopen(argv[1], "wb");
  if (out == nullptr) {
    std::perror(argv[1]);
    return 1;
  }
  fmt::memory_buffer buf;
  fmt::format_to(std::back_inserter(buf), "gx_dps\n");
  double bias_dps = 0.25;
  for (long long i = 0; i < n; ++i) {
    bias_dps += walk_step_dps * normal(rng);
    fmt::format_to(std::back_inserter(buf), "{:.7g}\n", bias_dps + white_dps * normal(rng));
    if (buf.size() > (1 << 20)) {
      std::fwrite(buf.data(), 1, buf.size(), out);
      buf.clear();
    }
  }
  std::fwrite(buf.data(), 1, buf.size(), out);
  return std::fclose(out) == 0 ? 0 : 1;
}
