// The one pair of conversion helpers between millimetres (double) and Clipper's 64-bit
// integer coordinates (mm × 1e6): integers live only inside polygon clipping.
#pragma once

#include <polyclipping/clipper.hpp>

#include <cmath>

#include "nonplanar/polygon.hpp"

namespace nonplanar::clip {

constexpr double kScale = 1e6;  // 1 nm resolution; ±9.2e12 mm range

inline ClipperLib::IntPoint to_clipper(const Vec2& p) {
  return {static_cast<ClipperLib::cInt>(std::llround(p.x() * kScale)),
          static_cast<ClipperLib::cInt>(std::llround(p.y() * kScale))};
}
inline Vec2 from_clipper(const ClipperLib::IntPoint& p) {
  return {static_cast<double>(p.X) / kScale, static_cast<double>(p.Y) / kScale};
}

}  // namespace nonplanar::clip
