// METRO_CHECK: stop loudly on a broken invariant (a programmer error, never bad input).
//
// Bad input is reported through metro::Error / metro::Result (status.hpp); METRO_CHECK is
// for conditions that cannot be false unless metro itself is wrong. It prints the file,
// line and condition to stderr and aborts, in every build type.
#pragma once

#include <cstdio>
#include <cstdlib>

#define METRO_CHECK(condition)                                                                 \
  do {                                                                                         \
    if (!(condition)) {                                                                        \
      std::fprintf(stderr, "%s:%d: METRO_CHECK failed: %s\n", __FILE__, __LINE__, #condition); \
      std::abort();                                                                            \
    }                                                                                          \
  } while (false)
