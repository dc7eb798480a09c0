// METRO_SIMD_CLONES: a function compiled twice, for AVX2 and for the x86-64 baseline, the
// loader choosing by the CPU (GCC's target_clones). Only for loops whose result does not
// depend on the vector width: the same operations in the same order on each path (lanes
// fixed in the source, or vectors across independent sums), and no FMA contraction (the
// "avx2" target has none), so both paths give the same bits.
//
// The sanitizer builds keep the default path only, so CI runs the tests on both paths (the
// plain build takes AVX2 on a CPU that has it). Under ThreadSanitizer the clones' resolver,
// instrumented, would run before the sanitizer's runtime starts (a crash at load).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define METRO_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define METRO_SIMD_CLONES
#endif
