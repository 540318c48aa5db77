#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar::paths {

std::vector<std::vector<Polygon>> perimeter_loops(const ExPolygons& island, int count, double w_ext,
                                                  double s, ExPolygons* inner) {
  std::vector<std::vector<Polygon>> loops;
  if (count <= 0) {
    *inner = island;
    return loops;
  }
  ExPolygons cur = clip::offset_ex(island, -0.5 * w_ext);
  for (int i = 0; i < count && !cur.empty(); ++i) {
    std::vector<Polygon> ring;
    for (const ExPolygon& e : cur) {
      ring.push_back(e.contour);
      for (const Polygon& h : e.holes) ring.push_back(h);
    }
    loops.push_back(std::move(ring));
    if (i + 1 < count) {
      ExPolygons next = clip::offset_ex(cur, -s);
      if (next.empty()) {
        *inner = {};
        return loops;
      }
      cur = std::move(next);
    }
  }
  *inner = cur.empty() ? ExPolygons{} : clip::offset_ex(cur, -0.5 * s);
  return loops;
}

}  // namespace nonplanar::paths
