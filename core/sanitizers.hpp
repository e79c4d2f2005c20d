// Whether this translation unit is compiled with AddressSanitizer: GCC defines
// __SANITIZE_ADDRESS__, clang answers __has_feature(address_sanitizer) instead.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define PINDRAG_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PINDRAG_ASAN 1
#endif
#endif
