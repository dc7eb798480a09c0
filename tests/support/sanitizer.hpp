// METRO_UNDER_SANITIZER: 1 when this file is compiled with AddressSanitizer or
// ThreadSanitizer (tests only). g++ says so with __SANITIZE_ADDRESS__ / __SANITIZE_THREAD__,
// clang, which builds CI's sanitizer tree, only through __has_feature.
#pragma once

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define METRO_UNDER_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define METRO_UNDER_SANITIZER 1
#endif
#endif
#ifndef METRO_UNDER_SANITIZER
#define METRO_UNDER_SANITIZER 0
#endif
