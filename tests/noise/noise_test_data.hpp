// Loaders for the public reference data in datasets/external (tests only; the data sets,
// their sources and licenses are listed in datasets/external/README.md).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace metro::testing {

// The path of a file under datasets/external, e.g. "ocxo_stable32/adev_octave.txt".
inline std::string ExternalDataPath(const std::string& relative) {
  return std::string(METRO_EXTERNAL_DATA_DIR) + "/" + relative;
}

// One number per line; lines starting with '#' and empty lines are skipped.
inline std::vector<double> ReadNumberColumn(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> v;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    v.push_back(std::strtod(line.c_str(), nullptr));
  }
  return v;
}

// A Stable32 table: "AF Tau # Alpha MinSigma Sigma MaxSigma" rows after '#' comments.
struct Stable32Row {
  int64_t af = 0;
  double tau_s = 0.0;
  int64_t n = 0;
  int alpha = 0;
  double min_sigma = 0.0;
  double sigma = 0.0;
  double max_sigma = 0.0;
};

inline std::vector<Stable32Row> ReadStable32(const std::string& path) {
  std::ifstream in(path);
  std::vector<Stable32Row> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Stable32Row r;
    if (s >> r.af >> r.tau_s >> r.n >> r.alpha >> r.min_sigma >> r.sigma >> r.max_sigma) {
      rows.push_back(r);
    }
  }
  return rows;
}

// NBS 1000-point frequency set (Riley; PHASE.DAT SOURCE.md): n_{i+1} = 16807 n_i mod
// (2^31 - 1), n_0 = 1234567890, y_i = n_i / (2^31 - 1), i = 0..999.
inline std::vector<double> Nbs1000Frequency() {
  std::vector<double> y;
  uint64_t n = 1234567890;
  for (int i = 0; i < 1000; ++i) {
    y.push_back(static_cast<double>(n) / 2147483647.0);
    n = (16807 * n) % 2147483647;
  }
  return y;
}

// The OCXO record as fractional frequency y = (f - 1e7) / 1e7 (allantools' conversion).
inline std::vector<double> OcxoFractionalFrequency() {
  std::vector<double> f = ReadNumberColumn(ExternalDataPath("ocxo_stable32/ocxo_frequency.txt"));
  for (double& v : f) v = (v - 1.0e7) / 1.0e7;
  return f;
}

}  // namespace metro::testing
