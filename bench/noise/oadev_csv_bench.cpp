// Whole-process benchmark: read a one-column CSV of rate samples (first line may be a
// header), compute the Allan curve (octave OADEV by default, with noise identification and
// Greenhall-Riley confidence intervals; metro::internal::ComputeAllanInPlace, the same
// result as metro::ComputeAllan) and print it.
//   metro_bench_noise_oadev FILE.csv [--taus octave|all|...] [--limit N] [--threads T]
//                           [--tau0 S]
// The CSV is mapped into memory and parsed (plain decimals by the session loader's exact
// fast path, anything else by fast_float) on all threads, each thread
// straight into its place in the one buffer that becomes the phase; the timings of each
// stage go to stderr, the curve to stdout.
#include <fast_float/fast_float.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/plain_decimal.hpp"
#include "metro/noise/allan.hpp"
#include "noise/allan_internal.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Parses the numbers of [begin, end) (one per line, blank lines skipped) into out[0..);
// returns how many, or -1 on a bad line or when more than `capacity` values are found.
int64_t ParseSlice(const char* begin, const char* end, double* out, int64_t capacity) {
  const char* p = begin;
  while (p < end && (*p == '\n' || *p == '\r')) ++p;
  int64_t count = 0;
  while (p < end) {
    if (count == capacity) return -1;
    // The plain-decimal fast path (bit-identical to fast_float), fast_float for the rest.
    const char* next = metro::internal::PlainDecimal(p, end, &out[count]);
    if (next == nullptr) {
      const fast_float::from_chars_result r = fast_float::from_chars(p, end, out[count]);
      if (r.ec != std::errc()) return -1;
      next = r.ptr;
    }
    ++count;
    p = next;
    if (p < end && *p != '\n' && *p != '\r') return -1;
    while (p < end && (*p == '\n' || *p == '\r')) ++p;
  }
  return count;
}

}  // namespace

int main(int argc, char** argv) {
  const Clock::time_point t_start = Clock::now();
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s FILE.csv [--taus SPACING] [--limit N] [--threads T]\n",
                 argv[0]);
    return 2;
  }
  std::string taus = "octave";
  long long limit = 0;
  int threads = 0;
  double tau0_s = 0.01;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--taus") {
      taus = argv[i + 1];
    } else if (flag == "--limit") {
      limit = std::atoll(argv[i + 1]);
    } else if (flag == "--threads") {
      threads = std::atoi(argv[i + 1]);
    } else if (flag == "--tau0") {
      tau0_s = std::atof(argv[i + 1]);
    } else {
      std::fprintf(stderr, "unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  const int fd = open(argv[1], O_RDONLY);
  struct stat st {};
  if (fd < 0 || fstat(fd, &st) != 0 || st.st_size == 0) {
    std::fprintf(stderr, "%s: cannot read\n", argv[1]);
    return 2;
  }
  const size_t size = static_cast<size_t>(st.st_size);
  void* map = mmap(nullptr, size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
  if (map == MAP_FAILED) {
    std::fprintf(stderr, "%s: mmap failed\n", argv[1]);
    return 2;
  }
  const Clock::time_point t_mapped = Clock::now();
  const char* data = static_cast<const char*>(map);
  const char* end = data + size;
  const char* body = data;
  if (body < end && !(std::isdigit(static_cast<unsigned char>(*body)) || *body == '-' ||
                      *body == '+' || *body == '.')) {
    body = static_cast<const char*>(std::memchr(body, '\n', size));
    body = body == nullptr ? end : body + 1;
  }
  // Split at line boundaries, one slice per thread.
  const int n_threads =
      threads > 0 ? threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<const char*> cut(static_cast<size_t>(n_threads) + 1, end);
  cut[0] = body;
  for (int t = 1; t < n_threads; ++t) {
    const char* p = body + (end - body) * t / n_threads;
    p = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
    cut[static_cast<size_t>(t)] = p == nullptr ? end : p + 1;
  }
  // A slice holds at most one value per line: size the result once, parse every
  // slice in place at its offset, then close the gaps left by blank lines (none usually).
  std::vector<int64_t> capacity(static_cast<size_t>(n_threads), 0);
  std::vector<int64_t> parsed(static_cast<size_t>(n_threads), 0);
  // buffer = [unused, y_0, ..., y_{M-1}]: the library turns it into the phase in place.
  // Not zero-filled: each parse thread is the first to touch (and fault in) its part.
  std::unique_ptr<double[]> buffer;
  {
    std::vector<std::thread> pool;
    for (int t = 0; t < n_threads; ++t) {
      pool.emplace_back([&, t] {
        const size_t k = static_cast<size_t>(t);
        const bool open_end = cut[k + 1] > cut[k] && cut[k + 1][-1] != '\n';
        capacity[k] = std::count(cut[k], cut[k + 1], '\n') + (open_end ? 1 : 0);
      });
    }
    for (std::thread& th : pool) th.join();
  }
  const Clock::time_point t_counted = Clock::now();
  std::vector<int64_t> offset(static_cast<size_t>(n_threads) + 1, 0);
  for (size_t k = 0; k < capacity.size(); ++k) offset[k + 1] = offset[k] + capacity[k];
  // Huge pages for the 80 MB of samples (THP "madvise" mode): far fewer page faults.
  const size_t capacity_total = static_cast<size_t>(offset.back()) + 1;
  buffer.reset(new double[capacity_total]);
  {
    constexpr uintptr_t kHuge = uintptr_t{2} << 20;
    const uintptr_t begin = reinterpret_cast<uintptr_t>(buffer.get());
    const uintptr_t lo = (begin + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t hi = (begin + capacity_total * sizeof(double)) & ~(kHuge - 1);
    if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
  }
  buffer[0] = 0.0;
  double* const samples = buffer.get() + 1;
  const Clock::time_point t_allocated = Clock::now();
  {
    std::vector<std::thread> pool;
    for (int t = 0; t < n_threads; ++t) {
      pool.emplace_back([&, t] {
        const size_t k = static_cast<size_t>(t);
        parsed[k] = ParseSlice(cut[k], cut[k + 1], samples + offset[k], capacity[k]);
      });
    }
    for (std::thread& th : pool) th.join();
  }
  size_t total = 0;
  for (size_t k = 0; k < parsed.size(); ++k) {
    if (parsed[k] < 0) {
      std::fprintf(stderr, "%s: a line is not a number\n", argv[1]);
      return 2;
    }
    if (static_cast<int64_t>(total) != offset[k]) {
      std::memmove(samples + total, samples + offset[k],
                   static_cast<size_t>(parsed[k]) * sizeof(double));
    }
    total += static_cast<size_t>(parsed[k]);
  }
  munmap(map, size);
  close(fd);
  if (limit > 0 && static_cast<size_t>(limit) < total) total = static_cast<size_t>(limit);
  const Clock::time_point t_parsed = Clock::now();

  metro::AllanOptions options;
  const metro::Result<metro::TauSpacing> spacing = metro::ParseTauSpacing(taus);
  if (!spacing.ok()) {
    std::fprintf(stderr, "%s\n", spacing.error().message.c_str());
    return 2;
  }
  options.taus = spacing.value();
  options.threads = threads;
  const metro::Result<metro::AllanCurve> curve = metro::internal::ComputeAllanInPlace(
      buffer.get(), static_cast<int64_t>(total) + 1, tau0_s, options);
  const Clock::time_point t_done = Clock::now();
  if (!curve.ok()) {
    std::fprintf(stderr, "%s\n", curve.error().message.c_str());
    return 1;
  }
  const metro::AllanCurve& c = curve.value();
  std::string text = "tau_s,oadev,ci_low,ci_high,edf,alpha\n";
  for (size_t i = 0; i < c.size(); ++i) {
    text += fmt::format("{:.6g},{:.6g},{:.6g},{:.6g},{:.4g},{}\n", c.tau_s[i], c.dev[i],
                        c.ci_low[i], c.ci_high[i], c.edf[i], c.alpha[i]);
  }
  std::fwrite(text.data(), 1, text.size(), stdout);
  std::fprintf(stderr,
               "metro: %zu samples, %zu taus (%s), threads %d: read+parse %.3f s (map %.3f, "
               "count lines %.3f, allocate %.3f, parse %.3f), Allan+EDF+CI %.3f s, in-process "
               "total %.3f s\n",
               total, c.size(), taus.c_str(), n_threads, Seconds(t_start, t_parsed),
               Seconds(t_start, t_mapped), Seconds(t_mapped, t_counted),
               Seconds(t_counted, t_allocated), Seconds(t_allocated, t_parsed),
               Seconds(t_parsed, t_done), Seconds(t_start, Clock::now()));
  return 0;
}
