// Geometry helpers for tests: closest point on a triangle and on a mesh, plane cuts of a mesh.
#pragma once

#include <algorithm>
#include <cmath>
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

/// Distances from points to one mesh (mm): every face looked at, but through its box, made
/// once, so most are passed over at a few comparisons (under the sanitizers the boxes made
/// anew per point took 25 s of one test).
class MeshDistance {
 public:
  explicit MeshDistance(const TriangleMesh& m) : m_(m) {
    box_.reserve(6 * m.faces.size());
    for (const auto& f : m.faces)
      for (int axis = 0; axis < 3; ++axis) {
        const double a = m.vertices[f[0]][axis], b = m.vertices[f[1]][axis],
                     c = m.vertices[f[2]][axis];
        box_.push_back(std::min({a, b, c}));
        box_.push_back(std::max({a, b, c}));
      }
  }
  double operator()(const Vec3& p) const {
    double best2 = 1e300;
    for (std::size_t i = 0; i < m_.faces.size(); ++i) {
      const double* b = &box_[6 * i];
      double d2 = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double out = std::max({b[2 * axis] - p[axis], 0.0, p[axis] - b[2 * axis + 1]});
        d2 += out * out;
      }
      if (d2 >= best2) continue;
      const auto& f = m_.faces[i];
      const Vec3 q =
          closest_on_triangle(p, m_.vertices[f[0]], m_.vertices[f[1]], m_.vertices[f[2]]);
      best2 = std::min(best2, (q - p).squaredNorm());
    }
    return std::sqrt(best2);
  }

 private:
  const TriangleMesh& m_;
  std::vector<double> box_;  ///< per face: x lo, x hi, y lo, y hi, z lo, z hi
};

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
