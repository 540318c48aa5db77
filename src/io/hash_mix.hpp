// One 64-bit mixing function for the readers' and the weld's hash tables.
#pragma once

#include <cstdint>

namespace nonplanar::io {

/// splitmix64's finaliser: every input bit reaches every output bit, so the low bits an
/// open-addressing table masks are well spread even for keys that differ only in their high
/// bits (the coordinates of a mesh made on a grid: 0.5 mm steps leave a float's low mantissa
/// bits zero).
inline std::uint64_t mix64(std::uint64_t h) {
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  return h ^ (h >> 31);
}

}  // namespace nonplanar::io
