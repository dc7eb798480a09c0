#include "metro/core/file.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>

namespace metro {
namespace {

TEST_CASE("SHA-256 of known strings", "[core]") {
  // FIPS 180-2 appendix B.1 and the empty string.
  CHECK(Sha256Hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(Sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST_CASE("WriteFileAtomically replaces a file and ReadFile reads it back", "[core]") {
  const std::string path = "metro_file_test_" + std::to_string(::getpid()) + ".txt";
  REQUIRE(WriteFileAtomically(path, "first").ok());
  REQUIRE(WriteFileAtomically(path, "second\n").ok());
  auto back = ReadFile(path);
  REQUIRE(back.ok());
  CHECK(back.value() == "second\n");
  CHECK(IsSameFile(path, "./" + path));
  std::remove(path.c_str());
}

TEST_CASE("File errors name the path", "[core]") {
  auto missing = ReadFile("/nonexistent/metro/x.csv");
  REQUIRE_FALSE(missing.ok());
  CHECK(missing.error().ToString().find("/nonexistent/metro/x.csv") != std::string::npos);
  auto dir_write = WriteFileAtomically("/nonexistent-dir/out.json", "{}");
  REQUIRE_FALSE(dir_write.ok());
  CHECK(dir_write.error().ToString().find("/nonexistent-dir/out.json") != std::string::npos);
}

}  // namespace
}  // namespace metro
