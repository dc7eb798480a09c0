#include "metro/core/file_lock.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <fstream>
#include <sstream>
#include <string>

#include "support/temp_file.hpp"

namespace metro {
namespace {

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_CASE("TryLockFile: one holder at a time, named by what it wrote", "[core]") {
  testing::WorkDir dir;
  const std::string path = dir / "run.lock";
  Result<FileLockAttempt> first = TryLockFile(path);
  REQUIRE(first.ok());
  REQUIRE(first.value().lock.has_value());
  const std::string who = ReadAll(path);
  CHECK(who.rfind("pid " + std::to_string(::getpid()) + " on ", 0) == 0);
  CHECK(who.find(", since ") != std::string::npos);
  {
    // flock locks belong to the open file description: a second open conflicts even in the
    // same process, as another program's would.
    Result<FileLockAttempt> second = TryLockFile(path);
    REQUIRE(second.ok());
    CHECK_FALSE(second.value().lock.has_value());
    CHECK(second.value().holder == who);
  }
  first.value().lock.reset();  // released
  Result<FileLockAttempt> third = TryLockFile(path);
  REQUIRE(third.ok());
  CHECK(third.value().lock.has_value());
}

TEST_CASE("TryLockFile: a lock file that cannot be created names itself", "[core]") {
  const Result<FileLockAttempt> r = TryLockFile("/nonexistent-dir/run.lock");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().file == "/nonexistent-dir/run.lock");
  CHECK(r.error().message.find("cannot create the lock file /nonexistent-dir/run.lock: ") == 0);
}

}  // namespace
}  // namespace metro
