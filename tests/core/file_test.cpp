#include "metro/core/file.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace metro {
namespace {

TEST_CASE("SHA-256 of known strings", "[core]") {
  // FIPS 180-2 appendix B.1 and the empty string.
  CHECK(Sha256Hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(Sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST_CASE("SHA-256 hashed in chunks is the one-shot digest and reports its progress", "[core]") {
  // FIPS 180-2 appendix B.2 and B.3 (one million 'a').
  const std::string b2 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
  const std::string b3(1000000, 'a');
  for (const size_t chunk : {size_t{1}, size_t{7}, size_t{64}, size_t{4096}, size_t{1} << 22}) {
    for (const auto& [text, digest] :
         {std::pair<const std::string&, const char*>{
              b2, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1"},
          std::pair<const std::string&, const char*>{
              b3, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0"}}) {
      if (chunk == 1 && text.size() > 1000) continue;  // A million calls prove nothing more.
      std::vector<size_t> reported;
      CHECK(Sha256Hex(text, chunk, [&](size_t n) { reported.push_back(n); }) == digest);
      REQUIRE(reported.size() == (text.size() + chunk - 1) / chunk);
      CHECK(reported.back() == text.size());
      for (size_t i = 0; i + 1 < reported.size(); ++i) CHECK(reported[i] == (i + 1) * chunk);
    }
  }
  size_t calls = 0;
  CHECK(Sha256Hex("", 0, [&](size_t) { ++calls; }) ==
        "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(calls == 0);
  CHECK(Sha256Hex("abc", 0, nullptr) ==
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
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
