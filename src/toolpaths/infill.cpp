#include <algorithm>
#include <cmath>

#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar::paths {
namespace {

// Offsets across the lines (t, along nrm) of the lines for an area spanning [tmin, tmax]: on
// the global grid, or fitted to the span (see infill_lines). *d gets their spacing.
std::vector<double> line_offsets(double tmin, double tmax, double spacing, bool fit, double* d) {
  std::vector<double> t;
  *d = spacing;
  if (!fit) {
    // Global phase: line k sits at t = (k + ½)·spacing, whatever the island.
    for (double k = std::floor(tmin / spacing - 0.5); (k + 0.5) * spacing <= tmax; k += 1)
      t.push_back((k + 0.5) * spacing);
    return t;
  }
  // A line on the extreme itself would be clipped away whole along a side parallel to it.
  constexpr double kInside = 0.005;  // mm
  tmin += kInside, tmax -= kInside;
  const double span = tmax - tmin;
  const double n = std::round(span / spacing);  // intervals
  if (n < 1) return {0.5 * (tmin + tmax)};
  *d = std::clamp(span / n, 0.8 * spacing, 1.2 * spacing);
  const double lead = 0.5 * (span - n * *d);  // > 0 only when clamped: centred
  for (int k = 0; k <= static_cast<int>(n); ++k) t.push_back(tmin + lead + k * *d);
  return t;
}

}  // namespace

std::vector<InfillLine> infill_lines(const ExPolygons& region, double angle_deg, double spacing,
                                     double s, bool fit) {
  const ExPolygons area = clip::offset_ex(region, -0.5 * s);
  if (area.empty() || !(spacing > 0)) return {};
  const double a = angle_deg * M_PI / 180.0;
  const Vec2 dir(std::cos(a), std::sin(a)), nrm(-std::sin(a), std::cos(a));
  // Each island apart when fitted, all at once on the global grid.
  std::vector<ExPolygons> parts;
  if (fit)
    for (const ExPolygon& e : area) parts.push_back({e});
  else
    parts.push_back(area);
  std::vector<InfillLine> out;
  for (const ExPolygons& part : parts) {
    // Extent of the part across (t) and along (u) the lines.
    double tmin = 1e300, tmax = -1e300, umin = 1e300, umax = -1e300;
    for (const ExPolygon& e : part)
      for (const Vec2& p : e.contour) {
        tmin = std::min(tmin, p.dot(nrm)), tmax = std::max(tmax, p.dot(nrm));
        umin = std::min(umin, p.dot(dir)), umax = std::max(umax, p.dot(dir));
      }
    double d = spacing;
    std::vector<Polyline> lines;
    for (double t : line_offsets(tmin, tmax, spacing, fit, &d))
      lines.push_back({t * nrm + (umin - 1) * dir, t * nrm + (umax + 1) * dir});
    // Beads are extruded along their centre line only, so a line clipped s/2 inside the region
    // would leave s/2 unfilled at each end: extend both ends back to the region's edge.
    for (Polyline& l : clip::clip_polylines(lines, part)) {
      if (l.size() < 2) continue;
      const Vec2 d0 = (l[0] - l[1]).normalized(), d1 = (l.back() - l[l.size() - 2]).normalized();
      if (d0.allFinite()) l.front() += 0.5 * s * d0;
      if (d1.allFinite()) l.back() += 0.5 * s * d1;
      out.push_back({std::move(l), d});
    }
  }
  return out;
}

}  // namespace nonplanar::paths
