#include <cmath>

#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar::paths {

std::vector<Polyline> infill_lines(const ExPolygons& region, double angle_deg, double spacing,
                                   double s) {
  const ExPolygons area = clip::offset_ex(region, -0.5 * s);
  if (area.empty() || !(spacing > 0)) return {};
  const double a = angle_deg * M_PI / 180.0;
  const Vec2 dir(std::cos(a), std::sin(a)), nrm(-std::sin(a), std::cos(a));
  // Extent of the region across (t) and along (u) the lines.
  double tmin = 1e300, tmax = -1e300, umin = 1e300, umax = -1e300;
  for (const ExPolygon& e : area)
    for (const Vec2& p : e.contour) {
      tmin = std::min(tmin, p.dot(nrm)), tmax = std::max(tmax, p.dot(nrm));
      umin = std::min(umin, p.dot(dir)), umax = std::max(umax, p.dot(dir));
    }
  std::vector<Polyline> lines;
  // Global phase: line k sits at t = (k + ½)·spacing, whatever the island.
  for (double k = std::floor(tmin / spacing - 0.5); (k + 0.5) * spacing <= tmax; k += 1) {
    const double t = (k + 0.5) * spacing;
    lines.push_back({t * nrm + (umin - 1) * dir, t * nrm + (umax + 1) * dir});
  }
  // Beads are extruded along their centre line only, so a line clipped s/2 inside the region
  // would leave s/2 unfilled at each end: extend both ends back to the region's edge.
  std::vector<Polyline> out = clip::clip_polylines(lines, area);
  for (Polyline& l : out) {
    if (l.size() < 2) continue;
    const Vec2 d0 = (l[0] - l[1]).normalized(), d1 = (l.back() - l[l.size() - 2]).normalized();
    if (d0.allFinite()) l.front() += 0.5 * s * d0;
    if (d1.allFinite()) l.back() += 0.5 * s * d1;
  }
  return out;
}

}  // namespace nonplanar::paths
