// Budget inputs that name a session: the file is known by its identity, not by its spelling
// (issue #39), so a session evaluated with the command line's load options is not loaded
// again with default ones, and a cached session is not loaded twice.
#include "metro/uncertainty/session_resolver.hpp"

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "support/temp_file.hpp"

namespace metro {
namespace {

// Ten readings of one tag whose rate column is named as a third-party logger names it; only
// --column 'gyro_x=gx_dps' makes it gx_dps. Mean 1.45, or 11.45 for `offset` 10.
std::string Readings(double offset) {
  std::string text = "t_s,sensor,gyro_x\n";
  for (int k = 0; k < 10; ++k) {
    text += std::to_string(0.01 * k) + ",1," + std::to_string(offset + 1.0 + 0.1 * k) + "\n";
  }
  return text;
}

// A folder with log.csv (Readings(0)) and a sub-folder for another spelling of its path.
struct Folder {
  Folder() {
    std::filesystem::create_directories(dir / "sub");
    testing::Put(path, Readings(0.0));
  }
  testing::WorkDir dir;
  std::string path = dir / "log.csv";
};

// The load options that make the logger's gyro_x column gx_dps.
LoadOptions GyroXLoad() {
  LoadOptions load;
  load.column_map.push_back({"gyro_x", "gx_dps"});
  return load;
}

TEST_CASE("Session resolver: another spelling of the evaluated file is that evaluation",
          "[uncertainty][budget]") {
  const Folder folder;
  const std::string& path = folder.path;
  const testing::WorkDir& dir = folder.dir;
  const LoadOptions load = GyroXLoad();
  Result<Session> session = LoadSession(path, load);
  REQUIRE(session.ok());
  Result<SessionTypeA> evaluated = EvaluateSessionTypeA(session.value(), {});
  REQUIRE(evaluated.ok());
  const SessionQuantityResolver resolve =
      MakeSessionQuantityResolver(session.value(), evaluated.value(), {});
  for (const std::string& spelling : {path, dir / "sub/../log.csv", "./" + path}) {
    INFO(spelling);
    const Result<TypeASummary> r = resolve({spelling, 1, "gx_dps"});
    // With default options the file has no gx_dps (the column is gyro_x).
    REQUIRE(r.ok());
    CHECK(r.value().mean == Approx(1.45).epsilon(1e-12));
    CHECK(r.value().n == 10);
  }
}

TEST_CASE("Session resolver: one load per file whatever its spelling", "[uncertainty][budget]") {
  const Folder folder;
  const std::string& path = folder.path;
  const testing::WorkDir& dir = folder.dir;
  const LoadOptions load = GyroXLoad();
  const SessionQuantityResolver resolve = MakeSessionQuantityResolver(path, load, {});
  const Result<TypeASummary> first = resolve({"", 1, "gx_dps"});
  REQUIRE(first.ok());
  CHECK(first.value().mean == Approx(1.45).epsilon(1e-12));
  // The file changes in place (same inode): a second spelling answers from the session
  // already loaded, so it still reads 1.45, not 11.45.
  testing::Put(path, Readings(10.0));
  const Result<TypeASummary> second = resolve({dir / "sub/../log.csv", 1, "gx_dps"});
  REQUIRE(second.ok());
  CHECK(second.value().mean == Approx(1.45).epsilon(1e-12));
  // Another file is loaded on its own.
  const std::string other = dir / "other.csv";
  testing::Put(other, Readings(10.0));
  const Result<TypeASummary> third = resolve({other, 1, "gx_dps"});
  REQUIRE(third.ok());
  CHECK(third.value().mean == Approx(11.45).epsilon(1e-12));
}

}  // namespace
}  // namespace metro
