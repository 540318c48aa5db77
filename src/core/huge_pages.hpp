// Large arrays fault in 4 KiB pages on first touch, and page faults are expensive on
// virtual machines (a third of load time on a 1M-triangle mesh here). Asking for
// transparent huge pages on a fresh buffer before touching it cuts the faults 512-fold.
#pragma once

#include <sys/mman.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace nonplanar {

/// Advise the kernel to back [p, p + bytes) with huge pages (only whole 2 MiB pages inside
/// the range; small ranges are left alone). Harmless where THP is off.
inline void advise_huge_pages(const void* p, std::size_t bytes) {
  constexpr std::uintptr_t kHuge = 2u << 20;
  if (bytes < 2 * kHuge) return;
  const auto a = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t lo = (a + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t hi = (a + bytes) & ~(kHuge - 1);
  if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
}

/// v.reserve(n), then the advice above on the new buffer (before anything touches it).
template <class T, class A>
void reserve_huge(std::vector<T, A>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

/// v = n copies of x, in a huge-page-advised buffer.
template <class T, class A>
void assign_huge(std::vector<T, A>& v, std::size_t n, const T& x) {
  std::vector<T, A>().swap(v);
  reserve_huge(v, n);
  v.assign(n, x);
}

/// s.reserve(n), the new room huge-page-advised: for a text written at once, as large as n.
inline void reserve_text(std::string& s, std::size_t n) {
  if (s.capacity() >= n) return;
  s.reserve(n);
  advise_huge_pages(s.data(), n);
}

/// The texts one after another in one string of their total size, huge-page-advised (a
/// G-code file put together by appends was copied into each larger buffer, its pages faulted
/// in each time).
inline std::string joined_huge(std::initializer_list<std::string_view> parts) {
  std::size_t n = 0;
  for (std::string_view p : parts) n += p.size();
  std::string out;
  reserve_text(out, n);
  for (std::string_view p : parts) out.append(p);
  return out;
}

/// Hands the whole pages of s[released, upto) back to the kernel (they read as zeros after),
/// and moves `released` on: for a text read once from front to back, whose read part is never
/// looked at again (the engine's G-code as it is mapped: 19 MB of the bunny's peak).
inline void release_read_pages(std::string& s, std::size_t upto, std::size_t& released) {
  constexpr std::uintptr_t kPage = 4096;
  upto = std::min(upto, s.size());
  if (upto <= released) return;
  const auto base = reinterpret_cast<std::uintptr_t>(s.data());
  const std::uintptr_t lo = (base + released + kPage - 1) & ~(kPage - 1);
  const std::uintptr_t hi = (base + upto) & ~(kPage - 1);
  if (hi <= lo) return;
  ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
  released = hi - base;
}

/// n copies of x in a huge-page-advised buffer (a raster, a grid: written all over at once).
template <class T>
std::vector<T> huge_vector(std::size_t n, const T& x) {
  std::vector<T> v;
  assign_huge(v, n, x);
  return v;
}

}  // namespace nonplanar
