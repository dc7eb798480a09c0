// Private: the vectorized reader of machine-written session.csv rows (AVX-512).
//
// A logger writes every column with a fixed number of decimals ("%.6f"), so in a run of
// rows each field's dot sits a fixed number of bytes before its end, column by column.
// DecimalRows reads such a run four fields per instruction: it finds every ',' and '\n'
// (64 bytes per compare), learns each column's decimals from the first row, then takes
// the 16 bytes ending at each field, keeps its digits, drops the dot by a per-column
// shuffle, sums the digits in pairs (10a + b, 100a + b, 10000a + b, 1e8 a + b) and divides
// the integer by 10^decimals. Every value is the integer m < 10^15 over an exact power of
// ten, one correctly rounded division: bit for bit what PlainDecimal and fast_float return.
// A run that does not fit (a field longer than 15 bytes, a column whose decimals change,
// an exponent, a blank or comment line, CR LF) is refused as a whole, before anything is
// written, and the caller reads it with the scalar parser.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace metro::internal {

// True if this CPU can run DecimalRows (AVX-512 F/BW/VL/DQ, BMI1/2 and POPCNT).
bool DecimalRowsAvailable();

// How many runs DecimalRows has read (not refused) in this process (for tests).
int64_t DecimalRowsRead();

// Reads the rows [begin, end) of a CSV with `fields` numeric fields per row into `values`
// (rows x fields, row-major). `end` must follow a '\n'; the 16 bytes before `begin` must be
// readable. Returns the number of rows, or -1 if the run does not fit (nothing usable was
// written). `separators` is scratch space, reused between calls.
int64_t DecimalRows(const char* begin, const char* end, int fields,
                    std::vector<uint32_t>* separators, std::vector<double>* values);

}  // namespace metro::internal
