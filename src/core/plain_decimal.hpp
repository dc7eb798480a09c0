// The plain-decimal fast path shared by the CSV readers (session loader, one-column
// benchmark reader): bit for bit what fast_float returns, for the commonest numbers only.
#pragma once

#include <cstdint>
#include <cstring>

namespace metro::internal {

// Exact powers of ten 10^0 .. 10^15 (all exactly representable in binary64).
constexpr double kPow10[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                             1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};

// The commonest number in a session file, a plain decimal "[-]d*[.d*]" with at most 15
// digits, parsed as m / 10^f with m and 10^f exact in binary64: one correctly rounded
// division, so the result is the correctly rounded value of the decimal, bit for bit what
// fast_float returns (this is Clinger's fast path, without its generality). Returns the
// end of the number, or nullptr for anything else (exponents, long mantissas, '+', inf,
// nan), which then goes to fast_float.
inline const char* PlainDecimal(const char* p, const char* e, double* out) {
  const bool negative = p < e && *p == '-';
  const char* q = p + (negative ? 1 : 0);
  uint64_t m = 0;
  int digits = 0;
  while (q < e && static_cast<unsigned>(*q - '0') < 10) {
    m = m * 10 + static_cast<unsigned>(*q++ - '0');
    ++digits;
  }
  int fraction = 0;
  if (q < e && *q == '.') {
    ++q;
    while (q < e && static_cast<unsigned>(*q - '0') < 10) {
      m = m * 10 + static_cast<unsigned>(*q++ - '0');
      ++fraction;
    }
  }
  digits += fraction;
  if (digits == 0 || digits > 15) return nullptr;
  if (q < e && (*q == 'e' || *q == 'E' || static_cast<unsigned>(*q - '0') < 10)) return nullptr;
  const double v = static_cast<double>(m) / kPow10[fraction];
  // -v without a branch (signs in a data file are as good as random): v >= +0, so setting
  // the sign bit is exact negation.
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits |= static_cast<uint64_t>(negative) << 63;
  std::memcpy(out, &bits, sizeof bits);
  return q;
}

}  // namespace metro::internal
