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

// NONPLANAR_TSAN_BUILD: ThreadSanitizer, which maps terabytes of shadow memory too.
#if defined(__SANITIZE_THREAD__)
#define NONPLANAR_TSAN_BUILD 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define NONPLANAR_TSAN_BUILD 1
#endif
#endif

// NONPLANAR_SHADOW_MEMORY: a sanitizer whose shadow memory leaves no room for RLIMIT_AS.
#if defined(NONPLANAR_ASAN) || defined(NONPLANAR_TSAN_BUILD)
#define NONPLANAR_SHADOW_MEMORY 1
#endif
