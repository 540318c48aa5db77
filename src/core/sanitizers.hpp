// Which sanitizer this build runs under, for the few things that cannot work beside one.
#pragma once

// NONPLANAR_ASAN: AddressSanitizer, which reserves terabytes of address space (RLIMIT_AS
// cannot work under it). GCC defines __SANITIZE_ADDRESS__; clang answers __has_feature.
#if defined(__SANITIZE_ADDRESS__)
#define NONPLANAR_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define NONPLANAR_ASAN 1
#endif
#endif
