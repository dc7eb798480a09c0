// libFuzzer target for the session loaders (session.csv and receiver capture, strict and
// lenient). Any input must give a Session or an Error: never a crash, a hang, an
// out-of-bounds read (ASan) or undefined behaviour (UBSan).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "metro/io/session_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = "/tmp/metro_fuzz_" + std::to_string(::getpid()) + ".csv";
  FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  std::fwrite(data, 1, size, f);
  std::fclose(f);
  for (metro::SessionFormat format :
       {metro::SessionFormat::kAuto, metro::SessionFormat::kCsv, metro::SessionFormat::kReceiver}) {
    for (bool lenient : {false, true}) {
      metro::LoadOptions options;
      options.format = format;
      options.lenient = lenient;
      options.threads = 2;
      auto session = metro::LoadSession(path, options);
      if (session.ok()) {
        // Everything loaded must be consistent.
        for (const metro::Tag& tag : session.value().tags) {
          for (const metro::Quantity& q : tag.quantities) {
            if (q.values.size() != tag.t_s.size()) __builtin_trap();
          }
          for (size_t i = 1; i < tag.t_s.size(); ++i) {
            if (!(tag.t_s[i] > tag.t_s[i - 1])) __builtin_trap();
          }
        }
        (void)metro::FormatSessionCsv(session.value());
      }
    }
  }
  return 0;
}
