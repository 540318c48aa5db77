// Boolean and offset operations on polygons with holes (Clipper 6.4 underneath).
#pragma once

#include <vector>

#include "nonplanar/polygon.hpp"

namespace nonplanar::clip {

using ExPolygons = std::vector<ExPolygon>;
using Polyline = std::vector<Vec2>;

/// Union of closed loops under the non-zero rule (overlapping shells merge).
ExPolygons union_loops(const std::vector<Polygon>& loops);
ExPolygons union_ex(const ExPolygons& a);
ExPolygons diff_ex(const ExPolygons& a, const ExPolygons& b);
ExPolygons intersection_ex(const ExPolygons& a, const ExPolygons& b);
/// Grow (delta > 0) or shrink (delta < 0) by delta mm, mitred corners (limit 3).
ExPolygons offset_ex(const ExPolygons& a, double delta);
/// The parts of open polylines inside the region.
std::vector<Polyline> clip_polylines(const std::vector<Polyline>& lines, const ExPolygons& region);
/// Removes vertices closer than `tolerance` mm to their neighbours.
ExPolygons simplify(const ExPolygons& a, double tolerance);

}  // namespace nonplanar::clip
