#include "io/decimal_rows.hpp"

#include <atomic>
#include <cstring>
#include <numeric>

#include "core/plain_decimal.hpp"

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define METRO_DECIMAL_ROWS 1
#include <immintrin.h>
#endif

namespace metro::internal {

namespace {
std::atomic<int64_t> runs_read{0};
}  // namespace

int64_t DecimalRowsRead() { return runs_read.load(); }

#ifdef METRO_DECIMAL_ROWS

// GCC 12 warns that the AVX-512 intrinsics' own undefined pass-through operands
// (_mm512_undefined_*) "may be used uninitialized" when they are inlined here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

namespace {

#define METRO_AVX512 __attribute__((target("avx512f,avx512bw,avx512vl,avx512dq,bmi,bmi2,popcnt")))

// The offsets of every ',' and '\n' in [text, text + n) into (*separators)[1..], after a
// sentinel (*separators)[0] = -1, so that field j spans [sep[j] + 1, sep[j + 1]). Returns
// the number of separators and sets *newlines.
METRO_AVX512 size_t FindSeparators(const char* text, size_t n, std::vector<uint32_t>* separators,
                                   size_t* newlines) {
  // At most one separator per byte, and each 64-byte step writes 12 entries unconditionally.
  if (separators->size() < n + 16) separators->resize(n + 16);
  uint32_t* out = separators->data();
  out[0] = UINT32_MAX;
  size_t count = 1;
  size_t lines = 0;
  const __m512i comma = _mm512_set1_epi8(',');
  const __m512i lf = _mm512_set1_epi8('\n');
  for (size_t o = 0; o < n; o += 64) {
    const __mmask64 live = n - o >= 64 ? ~uint64_t{0} : _bzhi_u64(~uint64_t{0}, n - o);
    const __m512i v = _mm512_maskz_loadu_epi8(live, text + o);
    const uint64_t at_lf = _mm512_mask_cmpeq_epi8_mask(live, v, lf);
    uint64_t mask = _mm512_mask_cmpeq_epi8_mask(live, v, comma) | at_lf;
    lines += static_cast<size_t>(_mm_popcnt_u64(at_lf));
    const uint32_t found = static_cast<uint32_t>(_mm_popcnt_u64(mask));
    uint32_t* w = out + count;
    const uint32_t base = static_cast<uint32_t>(o);
    // Twelve positions without a branch (a session row has about one field per 8 bytes);
    // past the last separator tzcnt gives 64, written but not counted.
    for (uint32_t k = 0; k < 12; ++k) {
      w[k] = base + static_cast<uint32_t>(_tzcnt_u64(mask));
      mask = _blsr_u64(mask);
    }
    for (uint32_t k = 12; k < found; ++k) {
      w[k] = base + static_cast<uint32_t>(_tzcnt_u64(mask));
      mask = _blsr_u64(mask);
    }
    count += found;
  }
  *newlines = lines;
  return count - 1;
}

// Four consecutive fields of the flat field stream (the column pattern repeats every
// `period` groups): the shuffle that drops each field's dot, the dots' bit positions in
// the 64-byte register, and each field's 10^decimals.
struct Group {
  uint8_t shuffle[64];
  double scale[4];
  uint64_t dots;
};

// Each column's decimals, learned from the first row: -1 for a column without a dot.
// False if a column's dot is not followed by 1..14 digits.
bool LearnDecimals(const char* text, const uint32_t* sep, int fields, std::vector<int>* decimals) {
  decimals->assign(static_cast<size_t>(fields), -1);
  for (int c = 0; c < fields; ++c) {
    const char* b = text + static_cast<uint32_t>(sep[c] + 1);
    const char* e = text + sep[c + 1];
    const void* dot = std::memchr(b, '.', static_cast<size_t>(e - b));
    if (dot == nullptr) continue;
    const int d = static_cast<int>(e - static_cast<const char*>(dot)) - 1;
    if (d < 1 || d > 14) return false;
    (*decimals)[static_cast<size_t>(c)] = d;
  }
  return true;
}

std::vector<Group> MakeGroups(const std::vector<int>& decimals) {
  const int fields = static_cast<int>(decimals.size());
  std::vector<Group> groups(static_cast<size_t>(fields / std::gcd(fields, 4)));
  for (size_t g = 0; g < groups.size(); ++g) {
    uint8_t* shuffle = groups[g].shuffle;
    double* scale = groups[g].scale;
    uint64_t dots = 0;
    for (int i = 0; i < 4; ++i) {
      const int d = decimals[(g * 4 + static_cast<size_t>(i)) % static_cast<size_t>(fields)];
      // The field ends at byte 15 of its lane; its dot is at 15 - d. Bytes up to the dot
      // move one place right (0x80: a zero enters at byte 0), so the digits end at byte 15.
      const int dot = d < 0 ? -1 : 15 - d;
      for (int j = 0; j < 16; ++j) {
        const int src = j <= dot ? j - 1 : j;
        shuffle[i * 16 + j] = src < 0 ? 0x80 : static_cast<uint8_t>(src);
      }
      scale[i] = kPow10[d < 0 ? 0 : d];
      if (dot >= 0) dots |= uint64_t{1} << (i * 16 + dot);
    }
    groups[g].dots = dots;
  }
  return groups;
}

// Converts fields [0, n) (n a multiple of 4) of the stream into out. False if any field is
// not: an optional '-', then 1..15 bytes of digits with the column's dot (or none) in place.
METRO_AVX512 bool ConvertFields(const char* text, const uint32_t* sep, size_t n,
                                const std::vector<Group>& groups, double* out) {
  const __m512i iota =
      _mm512_set_epi8(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0, 15, 14, 13, 12, 11, 10,
                      9, 8, 7, 6, 5, 4, 3, 2, 1, 0, 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2,
                      1, 0, 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
  const __m512i lane_of_dword = _mm512_set_epi32(3, 3, 3, 3, 2, 2, 2, 2, 1, 1, 1, 1, 0, 0, 0, 0);
  const __m512i zero = _mm512_setzero_si512();
  const __m512i tens = _mm512_set1_epi16(0x010a);               // Bytes 10, 1.
  const __m512i hundreds = _mm512_set1_epi32(0x00010064);       // Words 100, 1.
  const __m512i ten_thousands = _mm512_set1_epi32(0x00012710);  // Words 10000, 1.
  const __m512i e8 = _mm512_set1_epi64(100000000);
  const __m512i first_of_lane = _mm512_set_epi64(6, 4, 2, 0, 6, 4, 2, 0);
  const __m256d sign = _mm256_set1_pd(-0.0);
  constexpr uint64_t kLastByte = 0x8000800080008000ull;
  uint64_t bad = 0;
  size_t g = 0;
  for (size_t j = 0; j < n; j += 4) {
    const Group& group = groups[g];
    g = g + 1 == groups.size() ? 0 : g + 1;
    const __m128i end = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sep + j + 1));
    const __m128i before = _mm_loadu_si128(reinterpret_cast<const __m128i*>(sep + j));
    const __m128i length = _mm_sub_epi32(_mm_sub_epi32(end, before), _mm_set1_epi32(1));
    // The mask has 4 bits; "& 0xF" keeps GCC 12 under ThreadSanitizer, which widened the
    // k-register with garbage above bit 7, from refusing every run.
    bad |= _mm_cmpgt_epi32_mask(length, _mm_set1_epi32(15)) & 0xFu;
    // Lane i: the 16 bytes that end where field j + i ends.
    __m512i v = _mm512_zextsi128_si512(
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(text + sep[j + 1] - 16)));
    v = _mm512_inserti32x4(
        v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(text + sep[j + 2] - 16)), 1);
    v = _mm512_inserti32x4(
        v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(text + sep[j + 3] - 16)), 2);
    v = _mm512_inserti32x4(
        v, _mm_loadu_si128(reinterpret_cast<const __m128i*>(text + sep[j + 4] - 16)), 3);
    // The field's first byte in each lane (16 - length), in every byte of the lane.
    const __m128i first = _mm_sub_epi32(_mm_set1_epi32(16), length);
    const __m512i first_bytes = _mm512_shuffle_epi8(
        _mm512_permutexvar_epi32(lane_of_dword, _mm512_zextsi128_si512(first)), zero);
    const uint64_t in_field = _mm512_cmpge_epu8_mask(iota, first_bytes);
    const uint64_t at_first = _mm512_cmpeq_epi8_mask(iota, first_bytes);
    const uint64_t minus = _mm512_mask_cmpeq_epi8_mask(at_first, v, _mm512_set1_epi8('-'));
    const __m512i digit = _mm512_sub_epi8(v, _mm512_set1_epi8('0'));
    const uint64_t is_digit = _mm512_cmple_epu8_mask(digit, _mm512_set1_epi8(9));
    const uint64_t is_dot = _mm512_cmpeq_epi8_mask(v, _mm512_set1_epi8('.'));
    const uint64_t body = in_field & ~minus;
    // Digits everywhere in the body but the column's dot, that dot inside the body, and a
    // digit last (so no field is empty, "-" or "-.").
    bad |= (body & ~group.dots & ~is_digit) | (group.dots & ~(is_dot & body)) |
           (~is_digit & kLastByte);
    __m512i x = _mm512_maskz_mov_epi8(is_digit & in_field, digit);
    x = _mm512_shuffle_epi8(x, _mm512_loadu_si512(group.shuffle));
    // Digits to integers: pairs (10a + b), quads (100a + b), octets (10000a + b), then
    // 1e8 * high octet + low octet in the lane's first 64 bits (at most 15 digits: exact).
    const __m512i quads = _mm512_madd_epi16(_mm512_maddubs_epi16(x, tens), hundreds);
    const __m512i octets = _mm512_madd_epi16(_mm512_packus_epi32(quads, quads), ten_thousands);
    const __m512i m = _mm512_add_epi64(_mm512_mul_epu32(octets, e8), _mm512_srli_epi64(octets, 32));
    const __m256d mantissa =
        _mm512_castpd512_pd256(_mm512_permutexvar_pd(first_of_lane, _mm512_cvtepu64_pd(m)));
    __m256d value = _mm256_div_pd(mantissa, _mm256_loadu_pd(group.scale));
    const __m512i minus_bytes = _mm512_movm_epi8(minus);
    const uint32_t q = _mm512_test_epi64_mask(minus_bytes, minus_bytes);
    const __mmask8 negative = static_cast<__mmask8>(_pext_u32(q | (q >> 1), 0x55));
    value = _mm256_mask_xor_pd(value, negative, value, sign);
    _mm256_storeu_pd(out + j, value);
  }
  return bad == 0;
}

METRO_AVX512 int64_t DecimalRowsAvx512(const char* begin, const char* end, int fields,
                                       std::vector<uint32_t>* separators,
                                       std::vector<double>* values) {
  const size_t n = static_cast<size_t>(end - begin);
  if (fields < 1 || n == 0 || end[-1] != '\n' || n > UINT32_MAX / 2) return -1;
  size_t rows = 0;
  const size_t count = FindSeparators(begin, n, separators, &rows);
  const uint32_t* sep = separators->data();
  // Every row: fields - 1 commas, then '\n'.
  if (count != rows * static_cast<size_t>(fields)) return -1;
  for (size_t r = 1; r <= rows; ++r) {
    if (begin[sep[r * static_cast<size_t>(fields)]] != '\n') return -1;
  }
  std::vector<int> decimals;
  if (!LearnDecimals(begin, sep, fields, &decimals)) return -1;
  const std::vector<Group> groups = MakeGroups(decimals);
  if (values->size() < count) values->resize(count);
  double* out = values->data();
  const size_t vectorized = count / 4 * 4;
  if (!ConvertFields(begin, sep, vectorized, groups, out)) return -1;
  for (size_t j = vectorized; j < count; ++j) {
    const char* b = begin + static_cast<uint32_t>(sep[j] + 1);
    const char* e = begin + sep[j + 1];
    if (PlainDecimal(b, e, out + j) != e) return -1;
  }
  return static_cast<int64_t>(rows);
}

}  // namespace

bool DecimalRowsAvailable() {
  static const bool available =
      __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
      __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("bmi2");
  return available;
}

int64_t DecimalRows(const char* begin, const char* end, int fields,
                    std::vector<uint32_t>* separators, std::vector<double>* values) {
  if (!DecimalRowsAvailable()) return -1;
  const int64_t rows = DecimalRowsAvx512(begin, end, fields, separators, values);
  if (rows >= 0) runs_read.fetch_add(1, std::memory_order_relaxed);
  return rows;
}

#pragma GCC diagnostic pop

#else

bool DecimalRowsAvailable() { return false; }

int64_t DecimalRows(const char*, const char*, int, std::vector<uint32_t>*, std::vector<double>*) {
  return -1;
}

#endif

}  // namespace metro::internal
