#include "io/decimal_rows.hpp"

#include <fast_float/fast_float.h>
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace metro::internal {
namespace {

// DecimalRows reads the 16 bytes before a field's end: the rows follow a 16-byte prefix.
constexpr size_t kPrefix = 16;

struct Run {
  int64_t rows = -1;
  std::vector<double> values;
};

Run Read(const std::string& rows, int fields) {
  const std::string text = std::string(kPrefix, 'x') + rows;
  std::vector<uint32_t> separators;
  Run run;
  run.rows = DecimalRows(text.data() + kPrefix, text.data() + text.size(), fields, &separators,
                         &run.values);
  return run;
}

// Every field of `rows` parsed by fast_float, the independent reference.
std::vector<double> Reference(const std::string& rows) {
  std::vector<double> out;
  const char* p = rows.data();
  const char* end = p + rows.size();
  while (p < end) {
    const char* e = p;
    while (*e != ',' && *e != '\n') ++e;
    double v = 0.0;
    const auto r = fast_float::from_chars(p, e, v);
    REQUIRE(r.ptr == e);
    out.push_back(v);
    p = e + 1;
  }
  return out;
}

// Bit for bit: -0.0 is not 0.0.
bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST_CASE("DecimalRows reads logger rows bit for bit as fast_float does", "[io][csv]") {
  if (!DecimalRowsAvailable()) {
    WARN("this CPU has no AVX-512: DecimalRows is not exercised (the scalar parser reads)");
    return;
  }
  std::mt19937_64 rng(20261121);
  for (const int fields : {1, 2, 3, 4, 5, 7, 9, 12}) {
    // Each column's decimals (-1: an integer column), fixed for the run as a logger's
    // format string fixes them.
    std::vector<int> decimals(static_cast<size_t>(fields));
    for (int& d : decimals) d = static_cast<int>(rng() % 10) - 1;
    for (int& d : decimals) d = d == 0 ? 6 : d;
    std::string rows;
    const int n = 1 + static_cast<int>(rng() % 400);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < fields; ++c) {
        const int d = decimals[static_cast<size_t>(c)];
        // At most 15 bytes with the sign and the dot: every field fits the vector reader.
        const int most = d < 0 ? 14 : 13 - d;
        const int int_digits = 1 + static_cast<int>(rng() % static_cast<unsigned>(most));
        std::string field = rng() % 2 == 0 ? "-" : "";
        for (int k = 0; k < int_digits; ++k) field += static_cast<char>('0' + rng() % 10);
        if (d > 0) {
          field += '.';
          for (int k = 0; k < d; ++k) field += static_cast<char>('0' + rng() % 10);
        }
        rows += field;
        rows += c + 1 == fields ? '\n' : ',';
      }
    }
    const std::vector<double> want = Reference(rows);
    const Run run = Read(rows, fields);
    INFO(fmt::format("{} fields, {} rows", fields, n));
    REQUIRE(run.rows == n);
    for (size_t i = 0; i < want.size(); ++i) {
      if (!SameBits(run.values[i], want[i])) {
        FAIL(fmt::format("field {}: {} vs {}", i, run.values[i], want[i]));
      }
    }
  }
}

TEST_CASE("DecimalRows keeps signs, zeros and the longest fields exact", "[io][csv]") {
  if (!DecimalRowsAvailable()) return;
  const std::string rows =
      "-0.000000,0,-0,123456789012345,007.50\n"
      "12345678.123456,-1,5,-12345678901234,-99.25\n"
      "0.000001,255,-7,1,0.05\n";
  const Run run = Read(rows, 5);
  REQUIRE(run.rows == 3);
  const std::vector<double> want = Reference(rows);
  for (size_t i = 0; i < want.size(); ++i) CHECK(SameBits(run.values[i], want[i]));
  CHECK(std::signbit(run.values[0]));  // -0.000000
  CHECK(std::signbit(run.values[2]));  // -0
  CHECK(run.values[3] == 123456789012345.0);
}

TEST_CASE("DecimalRows refuses runs it cannot read exactly", "[io][csv]") {
  if (!DecimalRowsAvailable()) return;
  const std::string good = "1.25,3,-0.500\n2.50,4,0.125\n";
  REQUIRE(Read(good, 3).rows == 2);
  // Each of these goes to the scalar parser (which explains or accepts it). The odd field
  // is in the second of three rows, among the fields read four at a time (the last
  // fields % 4 fields of a run go through PlainDecimal, exact for any plain decimal).
  for (std::string bad : {
           std::string("1.25,3,-0.500\n# comment\n2.50,4,0.125\n"),  // A comment line.
           std::string("1.25,3,-0.500\r\n2.50,4,0.125\r\n"),         // CR LF.
           std::string("1.25,3,-0.500\n\n2.50,4,0.125\n"),           // A blank line.
           std::string("1.25,3,-0.500\n2.5,4,0.125\n"),              // Decimals change.
           std::string("1.25,3,-0.500\n2.50,4.0,0.125\n"),           // A dot in an integer column.
           std::string("1.25,3,5e-1\n2.50,4,0.125\n"),               // An exponent.
           std::string("1.25,+3,-0.500\n2.50,4,0.125\n"),            // A plus sign.
           std::string("1.25,3,-0.500\n2.50,,0.125\n"),              // An empty field.
           std::string("1.25,3,-0.500\n2.50,-,0.125\n"),             // A lone minus.
           std::string("1.25,3,-0.500\n2.50,4,0..25\n"),             // Two dots.
           std::string("1.25,3,-0.500\n2.50,4,0.125,7\n"),           // An extra field.
           std::string("1.25,3,-0.500\n2.50,4\n"),                   // A missing field.
           std::string("1.25,3,-0.500\n2.50,4,0.125"),               // No final newline.
           std::string("1.25,1234567890123456,-0.500\n2.50,4,0.125\n"),  // 16 bytes.
           std::string("1.25,3,-0.500\n2.50,4,0 125\n"),                 // A space.
           std::string("1.25,3,-0.500\n2.50,4,0.1-5\n"),                 // A minus inside.
       }) {
    if (bad.back() == '\n') bad += "3.75,5,0.250\n";
    INFO(bad);
    CHECK(Read(bad, 3).rows == -1);
  }
}

}  // namespace
}  // namespace metro::internal
