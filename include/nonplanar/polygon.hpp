// Polygons in XY (mm): what slicing, toolpaths and layer planning exchange. The clipping
// itself (64-bit integer coordinates) stays inside core/polygon_ops.
#pragma once

#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// A closed polygon in XY (mm); contours counter-clockwise, holes clockwise.
using Polygon = std::vector<Vec2>;

struct ExPolygon {
  Polygon contour;
  std::vector<Polygon> holes;
};

/// Area of polygons with holes, mm².
double area(const std::vector<ExPolygon>& polys);

}  // namespace nonplanar
