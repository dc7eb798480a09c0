// Test helper: a uniquely named file in the build's working directory, removed when the
// object goes out of scope.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <string>

namespace metro::testing {

class TempFile {
 public:
  explicit TempFile(const std::string& contents, const std::string& suffix = ".csv") {
    static std::atomic<int> counter{0};
    path_ = "metro_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + suffix;
    std::ofstream out(path_, std::ios::binary);
    out << contents;
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace metro::testing
