// Test helpers: a uniquely named file in the build's working directory, removed when the
// object goes out of scope; a scratch folder per test program, removed when it ends.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

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

// A folder under the system's temporary directory named `prefix` and the process ID, made on
// the first call and removed with its contents when the test program ends; the path ends in
// '/'. One per prefix: each call site passes its own prefix (a function-local static).
inline std::string MakeScratchFolder(const std::string& prefix) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()));
  std::filesystem::create_directories(p);
  return p.string() + "/";
}

class ScratchFolder {
 public:
  explicit ScratchFolder(const std::string& prefix) : path_(MakeScratchFolder(prefix)) {}
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  ~ScratchFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A fresh folder in the working directory (the build's, under ctest), unique per instance,
// removed with its contents at the end; `dir / "name"` is a path inside it.
class WorkDir {
 public:
  WorkDir() {
    static std::atomic<int> counter{0};
    path = "metro_work_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  WorkDir(const WorkDir&) = delete;
  WorkDir& operator=(const WorkDir&) = delete;
  ~WorkDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return path + "/" + name; }
  std::string path;
};

// Writes `text` to `path` byte for byte (replacing it).
inline void Put(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A whole file's text ("" when it cannot be read).
inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace metro::testing
