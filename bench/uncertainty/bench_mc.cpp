// Monte Carlo benchmark: JCGM 101 9.5 gauge block (t, rectangular, normal, arcsine and
// curvilinear-trapezoid inputs), M trials, 99 % probabilistically symmetric and shortest
// intervals. Usage: bench_uncertainty_mc [TRIALS] [THREADS] [BUDGET.json]
// Prints one line: M, threads, y, u, shortest interval and the in-process time in seconds.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "metro/uncertainty/budget.hpp"
#include "metro/uncertainty/monte_carlo.hpp"

int main(int argc, char** argv) {
  const auto start = std::chrono::steady_clock::now();
  const int64_t trials = argc > 1 ? static_cast<int64_t>(std::atof(argv[1])) : 10000000;
  const int threads = argc > 2 ? std::atoi(argv[2]) : 0;
  const std::string path =
      argc > 3 ? argv[3]
               : std::string(METRO_SOURCE_DIR) + "/datasets/budgets/jcgm101_9_5_gauge_block.json";
  auto budget = metro::LoadBudget(path);
  if (!budget.ok()) {
    std::fprintf(stderr, "%s\n", budget.error().ToString().c_str());
    return 2;
  }
  metro::McOptions options = budget.value().monte_carlo;
  options.adaptive = false;
  options.trials = trials;
  options.threads = threads;
  auto result = metro::RunMonteCarlo(budget.value(), options);
  if (!result.ok()) {
    std::fprintf(stderr, "%s\n", result.error().ToString().c_str());
    return 1;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const metro::McResult& r = result.value();
  std::printf("metro M=%lld threads=%d mean=%.3f u=%.3f shortest=[%.2f, %.2f] time_s=%.3f\n",
              static_cast<long long>(r.trials), r.threads, r.value, r.u, r.shortest.low,
              r.shortest.high, seconds);
  return 0;
}
