// Notation as in top_direction.hpp.
#include "engine/top_direction.hpp"

#include <cmath>

namespace nonplanar {

std::optional<double> top_slope_direction(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                          double min_deg, double max_deg) {
  constexpr double kOnTop = 0.3;      // mm between a facet's centroid and H
  constexpr double kCoherent = 0.25;  // least (e₁ − e₂)/(e₁ + e₂)
  const double cos_min = std::cos(min_deg * M_PI / 180.0);
  const double cos_max = std::cos(max_deg * M_PI / 180.0);
  double jxx = 0, jxy = 0, jyy = 0;
  for (const auto& f : mesh.faces) {
    const Vec3 &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    const Vec3 n = (b - a).cross(c - a);
    const double twice_area = n.norm();
    if (!(twice_area > 0)) continue;
    const double nz = n.z() / twice_area;
    if (nz >= cos_min || nz <= cos_max) continue;  // flat, steep or facing down
    const Vec3 mid = (a + b + c) / 3.0;
    if (!plan.in_region(mid.x(), mid.y())) continue;
    if (std::abs(plan.top.height(mid.x(), mid.y()) - mid.z()) > kOnTop) continue;
    const Vec2 g = n.head<2>().normalized();
    jxx += twice_area * g.x() * g.x(), jxy += twice_area * g.x() * g.y();
    jyy += twice_area * g.y() * g.y();
  }
  const double trace = jxx + jyy;
  if (!(trace > 0)) return std::nullopt;
  // Eigenvalues of the 2×2 symmetric J: mean ± r.
  const double r = std::hypot(0.5 * (jxx - jyy), jxy);
  if (2 * r / trace < kCoherent) return std::nullopt;
  const double deg = 0.5 * std::atan2(2 * jxy, jxx - jyy) * 180.0 / M_PI;  // v₁'s angle
  return deg < 0 ? deg + 180.0 : deg;
}

}  // namespace nonplanar
