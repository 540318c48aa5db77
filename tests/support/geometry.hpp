// Geometry helpers for tests: closest point on a triangle, plane cuts of a mesh.
#pragma once

#include <algorithm>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar::test {

/// Closest point to p on triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
inline Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

inline double distance_to_mesh(const TriangleMesh& m, const Vec3& p) {
  double best = 1e300;
  for (const auto& f : m.faces) {
    const Vec3& a = m.vertices[f[0]];
    const Vec3& b = m.vertices[f[1]];
    const Vec3& c = m.vertices[f[2]];
    // Cheap reject by bounding box.
    const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const double dx = std::max({lo.x() - p.x(), 0.0, p.x() - hi.x()});
    const double dy = std::max({lo.y() - p.y(), 0.0, p.y() - hi.y()});
    const double dz = std::max({lo.z() - p.z(), 0.0, p.z() - hi.z()});
    if (dx * dx + dy * dy + dz * dz >= best * best) continue;
    best = std::min(best, (closest_on_triangle(p, a, b, c) - p).norm());
  }
  return best;
}

/// Points where the mesh's edges cross the plane z = h (one per crossing triangle edge).
inline std::vector<Vec3> plane_cut_points(const TriangleMesh& m, double h) {
  std::vector<Vec3> out;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      const Vec3& a = m.vertices[f[k]];
      const Vec3& b = m.vertices[f[(k + 1) % 3]];
      if ((a.z() - h) * (b.z() - h) < 0) out.push_back(a + (h - a.z()) / (b.z() - a.z()) * (b - a));
    }
  return out;
}

}  // namespace nonplanar::test
