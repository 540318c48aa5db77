// The stack's top on the facets: H(x, y), the height of a patch's triangles, carried outward
// past its rim.
//
// Notation: S_f the fitted NURBS top; H the facets' height (on the patch) or its continuation
// (off it); c the stack's bottom plane; S_i the stack's layers, S_0 = H, S_N = c.
//
// Why: the fit is smooth, the mesh is not. On a coarse mesh (the 1280-facet sphere) the fit
// through the vertices sits up to 0.04 mm above the facets and is steeper than any of them
// at the rim (33° against 29.7°). With S_0 = H the top layer lies on the printable facets
// themselves, whose slopes are below max_angle by the patch's definition, and the layers
// under it keep the fitted stack's proportions: S_i = c + (S_i,fit − c)·(H − c)/(S_0,fit − c).
// Off the patch the fit is held only by its smoothness term and can swing by millimetres
// (17 mm beside the sphere's rim); there H carries the rim's heights outward, so the blend
// zone sees a tame top that no clamp has to bend.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "nonplanar/analysis.hpp"

namespace nonplanar::layers {

/// The raster cell around (x, y) on nodes spaced `cell` from `origin` (nx·ny ≥ 2·2, node
/// (i, j) at index i·ny + j): its first node's index and the fractions (u, w) across it, held
/// at the raster's edge (values are constant past it).
struct RasterCell {
  std::size_t index;
  double u, w;
};
inline RasterCell raster_cell(const Vec2& origin, double cell, int nx, int ny, double x, double y) {
  const double fx = std::clamp((x - origin.x()) / cell, 0.0, nx - 1.0);
  const double fy = std::clamp((y - origin.y()) / cell, 0.0, ny - 1.0);
  const int i = std::clamp(static_cast<int>(std::floor(fx)), 0, nx - 2);
  const int j = std::clamp(static_cast<int>(std::floor(fy)), 0, ny - 2);
  return {static_cast<std::size_t>(i) * ny + j, fx - i, fy - j};
}

/// The bilinear interpolant at (x, y) of node values v on raster_cell's raster. T: double
/// heights, or NodeMask's ±1 bytes (the same arithmetic, so the same values as doubles).
template <class T>
double bilinear(const T* v, const Vec2& origin, double cell, int nx, int ny, double x, double y) {
  const auto [k, u, w] = raster_cell(origin, cell, nx, ny, x, y);
  const double p0 = v[k], p1 = v[k + 1], p2 = v[k + ny], p3 = v[k + ny + 1];
  return (1 - u) * ((1 - w) * p0 + w * p1) + u * ((1 - w) * p2 + w * p3);
}

struct FacetedTop {
  Vec2 origin{0, 0};  ///< node (0, 0), mm
  double cell = 0.1;  ///< node spacing, mm
  int nx = 0, ny = 0;
  std::vector<double> h;      ///< nx·ny node heights H, mm (node (i, j) at index i·ny + j)
  double h_lo = 0, h_hi = 0;  ///< the patch's height range (its vertices), mm
  bool empty() const { return h.empty(); }
  /// H at (x, y), bilinear between nodes, mm (constant past the raster's edge).
  double height(double x, double y) const;
  /// (∂H/∂x, ∂H/∂y) of the bilinear interpolant at (x, y).
  Vec2 gradient(double x, double y) const;
};

/// Inside (+1) or outside (−1) at each node of a raster, a byte a node: what a FacetedTop of
/// those heights holds in eight (a shell's region R on the bunny's raster: 2 MB, not 16).
struct NodeMask {
  Vec2 origin{0, 0};  ///< node (0, 0), mm
  double cell = 0.1;  ///< node spacing, mm
  int nx = 0, ny = 0;
  std::vector<signed char> in;  ///< nx·ny, +1 or −1 (node (i, j) at index i·ny + j)
  bool empty() const { return in.empty(); }
  /// The bilinear interpolant of the ±1 at (x, y) (>= 0: inside).
  double value(double x, double y) const { return bilinear(in.data(), origin, cell, nx, ny, x, y); }
  /// The same values as heights (for a contour of them; 8 bytes a node while it lives).
  FacetedTop as_top() const;
};

/// A NodeMask's signed chessboard distance: at each node, how many cells (diagonal steps count
/// 1) to the nearest node on the other side, + outside (−1 nodes), − inside; ±32767 where the
/// other side has no node. A node next to the other side holds ±1, so in every cell with both
/// sides the bilinear interpolant equals the mask's and elsewhere has its sign: the same zero
/// set, and it changes by at most one cell a cell along each axis (|∇| <= √2 cells per cell).
/// What a clip by the mask can step by: cell·value is at most √2 steep in mm per mm, and as far
/// above 0 as the region is away (the core of a shell the part stands above, engine route).
struct NodeDistance {
  Vec2 origin{0, 0};  ///< node (0, 0), mm
  double cell = 0.1;  ///< node spacing, mm
  int nx = 0, ny = 0;
  std::vector<std::int16_t> d;  ///< nx·ny, cells (node (i, j) at index i·ny + j)
  bool empty() const { return d.empty(); }
  /// The bilinear interpolant at (x, y), cells (constant past the raster's edge).
  double value(double x, double y) const { return bilinear(d.data(), origin, cell, nx, ny, x, y); }
};
NodeDistance signed_distance(const NodeMask& m);

/// Calls f(i, j, z) for every node (i, j) of t's raster (at t.origin + (i, j)·t.cell) inside
/// triangle abc seen from above, z its plane's height there; a vertical triangle covers none.
template <class F>
void for_each_node_in(const FacetedTop& t, const Vec3& a, const Vec3& b, const Vec3& c, F&& f) {
  const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
  if (d == 0) return;
  const Vec2 lo = (a.head<2>().cwiseMin(b.head<2>()).cwiseMin(c.head<2>()) - t.origin) / t.cell;
  const Vec2 hi = (a.head<2>().cwiseMax(b.head<2>()).cwiseMax(c.head<2>()) - t.origin) / t.cell;
  const int i0 = std::max(0, static_cast<int>(std::ceil(lo.x())));
  const int i1 = std::min(t.nx - 1, static_cast<int>(std::floor(hi.x())));
  const int j0 = std::max(0, static_cast<int>(std::ceil(lo.y())));
  const int j1 = std::min(t.ny - 1, static_cast<int>(std::floor(hi.y())));
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const Vec2 q = t.origin + Vec2(i, j) * t.cell;
      const double u = ((q.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (q.y() - a.y())) / d;
      const double v = ((b.x() - a.x()) * (q.y() - a.y()) - (q.x() - a.x()) * (b.y() - a.y())) / d;
      if (u < -1e-9 || v < -1e-9 || u + v > 1 + 1e-9) continue;
      f(i, j, a.z() + u * (b.z() - a.z()) + v * (c.z() - a.z()));
    }
}

/// A bound on H's slope over boxes, for a caller that can skip the points where it cannot
/// change sign. Within a cell the bilinear interpolant's ∂H/∂x is a mix of the cell's two
/// x-edge differences over the spacing (∂H/∂y likewise), so |∇H| there is at most the hypot of
/// the larger of each; kept as the largest over tiles of 16 × 16 cells.
class TopSlopeBound {
 public:
  explicit TopSlopeBound(const FacetedTop& t);
  /// At least |∇H| anywhere in the box [lo, hi] (mm per mm; past the raster's edge H is
  /// constant outward, as height() is); infinity for a raster with no cells or a node not
  /// finite.
  double over(const Vec2& lo, const Vec2& hi) const;

 private:
  static constexpr int kTile = 16;
  Vec2 origin_{0, 0};
  double cell_ = 1;
  int nx_ = 0, ny_ = 0;      ///< nodes, as the top's
  int tx_ = 0, ty_ = 0;      ///< tiles along x and y
  std::vector<double> max_;  ///< per tile (index i·ty + j), mm per mm
};

/// H on a raster of `cell` mm (coarser for huge patches: at most about 2 million nodes)
/// covering the patch's XY box grown by `pad` mm. Nodes inside a patch triangle (in XY) take
/// that triangle's height; the first ring outside continues its neighbours' triangles'
/// planes, within [h_lo, h_hi]; each later ring takes the mean of its 8 neighbours from
/// earlier rings, never rising or falling (past the first ring) faster than `max_slope` (dz per mm,
/// along the raster's axes and diagonals) from any of them; 20 Gauss–Seidel sweeps then smooth the
/// ridges where rings from different stretches of the rim meet (H levels off away from the rim).
FacetedTop faceted_top(const TriangleMesh& mesh, const Patch& patch, double cell, double pad,
                       double max_slope);

/// The facets' heights and slopes at points (x, y), without a raster: for each point with
/// want[k], the highest patch triangle containing it in XY, or else the nearest one (by
/// centroid, among those within a bucket of about four triangles' size) extended as a
/// plane. Points with !want[k], or farther than a bucket from the patch's box, get NaN. Also the
/// patch's vertex height range. mm; slopes dz/dx, dz/dy.
struct FacetSamples {
  std::vector<double> h;
  std::vector<Vec2> slope;
  double h_lo = 0, h_hi = 0;
};
FacetSamples facet_samples(const TriangleMesh& mesh, const Patch& patch,
                           const std::vector<Vec2>& xy, const std::vector<char>& want);

}  // namespace nonplanar::layers
