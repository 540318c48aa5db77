// Stage nurbs (paper §3–4): rational tensor-product B-spline surfaces, and the height-field
// fit of one patch, z = S(u, v).
//
// Notation (Piegl & Tiller, "The NURBS Book"): degrees p (in u) and q (in v); knot vectors
// U (n_u + p + 1 knots) and V (n_v + q + 1), clamped; control points P_ij and weights w_ij,
// i < n_u, j < n_v, stored row-major at i·n_v + j. N_i,p(u) are the B-spline basis functions;
// S(u, v) = Σ N_i,p(u) N_j,q(v) w_ij P_ij / Σ N_i,p(u) N_j,q(v) w_ij.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// A rational tensor-product B-spline surface. Invariants (checked by valid()):
/// U.size() == n_u + p + 1, V.size() == n_v + q + 1, knots non-decreasing,
/// points.size() == weights.size() == n_u · n_v, weights > 0.
struct NurbsSurface {
  int p = 3, q = 3;
  int n_u = 0, n_v = 0;
  std::vector<double> U, V;
  std::vector<Vec3> points;     ///< P_ij at i·n_v + j
  std::vector<double> weights;  ///< w_ij at i·n_v + j

  bool valid() const;
  const Vec3& P(int i, int j) const { return points[static_cast<std::size_t>(i) * n_v + j]; }
  double w(int i, int j) const { return weights[static_cast<std::size_t>(i) * n_v + j]; }

  /// S(u, v); u in [U[p], U[n_u]], v in [V[q], V[n_v]] (clamped to it).
  Vec3 evaluate(double u, double v) const;
  /// Partial derivatives up to order d (≤ 2): out[k][l] = ∂^(k+l) S / ∂u^k ∂v^l, k + l ≤ d.
  std::array<std::array<Vec3, 3>, 3> derivatives(double u, double v, int d) const;
  /// Unit normal S_u × S_v / |S_u × S_v| (zero where the surface is degenerate).
  Vec3 normal(double u, double v) const;

  /// Insert knot u r times (Boehm / Piegl & Tiller A5.3); the surface does not change.
  void insert_knot_u(double u, int r = 1);
  void insert_knot_v(double v, int r = 1);
};

/// A clamped, uniform knot vector of `spans` spans on [0, 1] for degree p.
std::vector<double> uniform_knots(int p, int spans);

/// A height field z = S_z(u, v) with (u, v) = ((x − x0) / sx, (y − y0) / sy): the z component
/// of the rational surface over the affine map of the XY footprint. The x, y of the control
/// points are the Greville abscissae mapped to XY, so the net can be drawn; with all weights
/// equal to 1 the full 3D surface reproduces x and y exactly.
struct HeightField {
  NurbsSurface surface;
  Vec2 origin{0, 0};  ///< (x0, y0), mm
  Vec2 extent{1, 1};  ///< (sx, sy), mm

  Vec2 uv(double x, double y) const {
    return {(x - origin.x()) / extent.x(), (y - origin.y()) / extent.y()};
  }
  /// z at (x, y), mm. Outside the footprint the surface is clamped to its border.
  double height(double x, double y) const;
  /// (∂z/∂x, ∂z/∂y) at (x, y).
  Vec2 gradient(double x, double y) const;
};

}  // namespace nonplanar
