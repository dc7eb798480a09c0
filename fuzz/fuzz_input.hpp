// Helpers shared by the fuzz targets.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace metro_fuzz {

// The fuzzer's bytes as a file, for library calls that take a path. The file lives alone in
// a private directory (mkdtemp), so a relative path inside a fuzzed document resolves next
// to it and finds nothing else; it is rewritten for every input and removed at exit.
// `name` is the file's name, e.g. "input.json".
inline const std::string& WriteInput(const uint8_t* data, size_t size, const char* name) {
  static std::string dir;
  static std::string path;
  if (path.empty()) {
    char tmpl[] = "/tmp/metro_fuzz_XXXXXX";
    if (::mkdtemp(tmpl) == nullptr) std::abort();
    dir = tmpl;
    path = dir + "/" + name;
    std::atexit([] {
      std::remove(path.c_str());
      ::rmdir(dir.c_str());
    });
  }
  FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

}  // namespace metro_fuzz
