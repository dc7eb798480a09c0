// A session file truncated or rewritten while it is loaded (issue #20, part 3): the load
// ends in one error naming the file and what happened, never SIGBUS and never a session
// made of half the file. The truncation is made from inside the load, on its first
// progress report, so it always lands while the file is being read.
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <string>

#include "metro/io/session_io.hpp"
#include "support/temp_file.hpp"

namespace metro {
namespace {

// A canonical session of `rows` rows, or the same numbers ';'-separated with decimal
// commas (the general loader).
std::string SessionText(int rows, bool semicolons) {
  std::string text = semicolons ? "t_s;sensor;gx_dps;gy_dps\n" : "t_s,sensor,gx_dps,gy_dps\n";
  for (int i = 0; i < rows; ++i) {
    std::string line = fmt::format("{}.{:02d},1,{}.{:03d},-0.{:03d}\n", i / 100, i % 100, i % 7,
                                   i % 1000, (3 * i) % 1000);
    if (semicolons) {
      for (char& c : line) c = c == ',' ? ';' : c == '.' ? ',' : c;
    }
    text += line;
  }
  return text;
}

TEST_CASE("A session truncated while it loads is an error naming the change", "[io][csv]") {
  for (bool semicolons : {false, true}) {
    INFO("semicolons " << semicolons);
    const std::string text = SessionText(1'500'000, semicolons);  // About 40 MB.
    testing::TempFile file(text, ".csv");
    const std::string path = file.path();
    std::atomic<bool> cut{false};
    std::atomic<int> truncated{-1};
    LoadOptions o;
    // From a parser thread: no Catch2 assertion here.
    o.on_bytes_parsed = [&cut, &truncated, &path](int64_t) {
      if (!cut.exchange(true)) truncated = ::truncate(path.c_str(), 4096);
    };
    Result<Session> s = LoadSession(path, o);
    REQUIRE(truncated.load() == 0);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().ToString() ==
          fmt::format("{}: the file changed while metro read it ({} bytes when opened, 4096 "
                      "bytes now; it shrank under the reader): nothing read from it is used; "
                      "read a file that no program is writing (copy it first, or wait for the "
                      "writer to finish)",
                      path, text.size()));
  }
}

}  // namespace
}  // namespace metro
