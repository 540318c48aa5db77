#include "layers/faceted_top.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/huge_pages.hpp"
#include "core/parallel.hpp"

namespace nonplanar::layers {
namespace {

// A patch triangle seen from above: which (x, y) it covers and its plane's height there.
// l1, l2 are the barycentric coordinates of b and c; d is twice the signed XY area (0: a
// vertical triangle, which covers nothing).
struct Facet {
  Vec3 a, b, c;
  double d;
  Facet(const TriangleMesh& m, int f)
      : a(m.vertices[m.faces[f][0]]),
        b(m.vertices[m.faces[f][1]]),
        c(m.vertices[m.faces[f][2]]),
        d((b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y())) {}
  double l1(double x, double y) const {
    return ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
  }
  double l2(double x, double y) const {
    return ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
  }
  bool covers(double x, double y) const {
    if (d == 0) return false;
    const double u = l1(x, y), v = l2(x, y);
    return u >= -1e-9 && v >= -1e-9 && u + v <= 1 + 1e-9;
  }
  /// The plane's height at (x, y), inside or not (d ≠ 0).
  double z(double x, double y) const {
    return a.z() + l1(x, y) * (b.z() - a.z()) + l2(x, y) * (c.z() - a.z());
  }
  Vec2 xy_min() const { return a.head<2>().cwiseMin(b.head<2>()).cwiseMin(c.head<2>()); }
  Vec2 xy_max() const { return a.head<2>().cwiseMax(b.head<2>()).cwiseMax(c.head<2>()); }
  Vec2 slope() const {
    const Vec3 n = (b - a).cross(c - a);
    return {-n.x() / n.z(), -n.y() / n.z()};
  }
};

// The patch's height range, from its vertices (so it does not depend on any raster).
void height_range(const TriangleMesh& mesh, const Patch& patch, double* lo, double* hi) {
  *lo = std::numeric_limits<double>::infinity(), *hi = -*lo;
  for (int f : patch.faces)
    for (int v : mesh.faces[f]) {
      *lo = std::min(*lo, mesh.vertices[v].z());
      *hi = std::max(*hi, mesh.vertices[v].z());
    }
}

// One Gauss–Seidel sweep, row by row and down each row, over the nodes of ring 2 and up:
// H = the mean of its four neighbours, the ones before it already this sweep's. Each update
// waits for the one before it in its row, so kRows rows go side by side, each a node behind
// the row before it: every node still reads the same values as in the plain row-by-row order
// (the row above is past it, the row below not yet there), and the CPU overlaps the rows'
// chains (the bunny's rasters of up to 2 million nodes, 20 sweeps each).
void relax(std::vector<double>& mz, const std::vector<int>& ring, int nx, int ny) {
  constexpr int kRows = 4;
  const auto update = [&](int i, int j) {
    const std::size_t q = static_cast<std::size_t>(i) * ny + j;
    if (ring[q] >= 2) mz[q] = 0.25 * (mz[q - ny] + mz[q + ny] + mz[q - 1] + mz[q + 1]);
  };
  for (int i0 = 1; i0 + 1 < nx; i0 += kRows) {
    const int rows = std::min(kRows, nx - 1 - i0);
    for (int step = 1; step + 1 < ny + rows - 1; ++step)
      for (int r = 0; r < rows; ++r)
        if (const int j = step - r; j >= 1 && j + 1 < ny) update(i0 + r, j);
  }
}

}  // namespace

double FacetedTop::height(double x, double y) const {
  return bilinear(h.data(), origin, cell, nx, ny, x, y);
}

FacetedTop NodeMask::as_top() const {
  FacetedTop t;
  t.origin = origin, t.cell = cell, t.nx = nx, t.ny = ny;
  t.h.assign(in.begin(), in.end());
  return t;
}

NodeDistance signed_distance(const NodeMask& m) {
  NodeDistance out;
  out.origin = m.origin, out.cell = m.cell, out.nx = m.nx, out.ny = m.ny;
  const std::size_t ny = static_cast<std::size_t>(m.ny), n = m.in.size();
  constexpr int kFar = 32767;
  // Two passes of the chessboard transform (each node from its 4 neighbours already passed),
  // once to the nearest inside node and once to the nearest outside one.
  auto transform = [&](signed char side) {
    std::vector<int> d(n);
    for (std::size_t k = 0; k < n; ++k) d[k] = m.in[k] == side ? 0 : kFar;
    auto relax = [&](long i, long j, long di, long dj, int& v) {
      const long a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= m.nx || b >= m.ny) return;
      v = std::min(v, d[static_cast<std::size_t>(a) * ny + static_cast<std::size_t>(b)] + 1);
    };
    for (long i = 0; i < m.nx; ++i)
      for (long j = 0; j < m.ny; ++j) {
        int& v = d[static_cast<std::size_t>(i) * ny + static_cast<std::size_t>(j)];
        relax(i, j, -1, -1, v), relax(i, j, -1, 0, v), relax(i, j, -1, 1, v), relax(i, j, 0, -1, v);
      }
    for (long i = m.nx - 1; i >= 0; --i)
      for (long j = m.ny - 1; j >= 0; --j) {
        int& v = d[static_cast<std::size_t>(i) * ny + static_cast<std::size_t>(j)];
        relax(i, j, 1, 1, v), relax(i, j, 1, 0, v), relax(i, j, 1, -1, v), relax(i, j, 0, 1, v);
      }
    return d;
  };
  const std::vector<int> to_in = transform(1), to_out = transform(-1);
  out.d.resize(n);
  for (std::size_t k = 0; k < n; ++k)
    out.d[k] = static_cast<std::int16_t>(std::min(kFar, m.in[k] > 0 ? to_out[k] : to_in[k]) *
                                         (m.in[k] > 0 ? -1 : 1));
  return out;
}

Vec2 FacetedTop::gradient(double x, double y) const {
  const auto [k, u, v] = raster_cell(origin, cell, nx, ny, x, y);
  const double* p = &h[k];
  return {((1 - v) * (p[ny] - p[0]) + v * (p[ny + 1] - p[1])) / cell,
          ((1 - u) * (p[1] - p[0]) + u * (p[ny + 1] - p[ny])) / cell};
}

TopSlopeBound::TopSlopeBound(const FacetedTop& t)
    : origin_(t.origin), cell_(t.cell), nx_(t.nx), ny_(t.ny) {
  if (nx_ < 2 || ny_ < 2 || t.h.size() != static_cast<std::size_t>(nx_) * ny_) return;
  tx_ = (nx_ - 2) / kTile + 1, ty_ = (ny_ - 2) / kTile + 1;
  max_.assign(static_cast<std::size_t>(tx_) * ty_, 0.0);
  const auto at = [&](int i, int j) { return t.h[static_cast<std::size_t>(i) * ny_ + j]; };
  for (int i = 0; i + 1 < nx_; ++i)
    for (int j = 0; j + 1 < ny_; ++j) {
      const double p00 = at(i, j), p01 = at(i, j + 1), p10 = at(i + 1, j), p11 = at(i + 1, j + 1);
      const double gx = std::max(std::abs(p10 - p00), std::abs(p11 - p01));
      const double gy = std::max(std::abs(p01 - p00), std::abs(p11 - p10));
      const bool finite = std::isfinite(p00 + p01 + p10 + p11);
      const double g =
          finite ? std::hypot(gx, gy) / cell_ : std::numeric_limits<double>::infinity();
      double& tile = max_[static_cast<std::size_t>(i / kTile) * ty_ + j / kTile];
      tile = std::max(tile, g);
    }
}

double TopSlopeBound::over(const Vec2& lo, const Vec2& hi) const {
  if (max_.empty()) return std::numeric_limits<double>::infinity();
  // The cells raster_cell() would use for the box's corners, and every cell between.
  auto cell_of = [&](double v, double o, int n) {
    const double f = std::clamp((v - o) / cell_, 0.0, n - 1.0);
    return std::clamp(static_cast<int>(std::floor(f)), 0, n - 2);
  };
  const int i0 = cell_of(lo.x(), origin_.x(), nx_) / kTile;
  const int i1 = cell_of(hi.x(), origin_.x(), nx_) / kTile;
  const int j0 = cell_of(lo.y(), origin_.y(), ny_) / kTile;
  const int j1 = cell_of(hi.y(), origin_.y(), ny_) / kTile;
  double g = 0;
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) g = std::max(g, max_[static_cast<std::size_t>(i) * ty_ + j]);
  return g;
}

FacetedTop faceted_top(const TriangleMesh& mesh, const Patch& patch, double cell, double pad,
                       double max_slope) {
  FacetedTop t;
  // Keep the raster under about 2 million nodes (16 MB) however large the patch.
  const Vec2 size = patch.xy_max - patch.xy_min + Vec2(2 * pad, 2 * pad);
  t.cell = std::max(cell, std::sqrt(size.x() * size.y() / 2e6));
  t.origin = patch.xy_min - Vec2(pad, pad);
  t.nx = static_cast<int>(std::ceil((size.x()) / t.cell)) + 1;
  t.ny = static_cast<int>(std::ceil((size.y()) / t.cell)) + 1;
  const std::size_t n = static_cast<std::size_t>(t.nx) * t.ny;
  const double lowest = -std::numeric_limits<double>::infinity();
  // Written all over at once: huge pages (a page fault each 4 KiB cost a third of it).
  std::vector<double> mz = huge_vector(n, lowest);
  std::vector<int> face = huge_vector(n, -1);  ///< the triangle that gave mz
  // The triangles' heights at the nodes inside them (the highest where two overlap in XY).
  for (int f : patch.faces) {
    const auto& v = mesh.faces[f];
    for_each_node_in(t, mesh.vertices[v[0]], mesh.vertices[v[1]], mesh.vertices[v[2]],
                     [&](int i, int j, double z) {
                       const std::size_t q = static_cast<std::size_t>(i) * t.ny + j;
                       if (z > mz[q]) mz[q] = z, face[q] = f;
                     });
  }
  // H: the triangles' heights (ring 0), then carried outward ring by ring.
  std::vector<int> ring = huge_vector(n, -1);
  std::vector<std::size_t> front;
  double h_lo = 0, h_hi = 0;
  height_range(mesh, patch, &h_lo, &h_hi);
  bool any = false;
  for (std::size_t k = 0; k < n; ++k)
    if (mz[k] > lowest) ring[k] = 0, any = true;
  if (!any) return {};  // no node falls inside the patch: the caller keeps the fit
  // Ring 0's front: its nodes beside a node off the patch, in order (the others have no
  // neighbour the next ring could take: the bunny's and the sine roof's patches are most of
  // their rasters, and a front of all their nodes took a third of this function).
  for (int i = 0; i < t.nx; ++i)
    for (int j = 0; j < t.ny; ++j) {
      const std::size_t q = static_cast<std::size_t>(i) * t.ny + j;
      if (ring[q] != 0) continue;
      bool rim = false;
      for (int di = -1; di <= 1 && !rim; ++di)
        for (int dj = -1; dj <= 1 && !rim; ++dj) {
          const int i2 = i + di, j2 = j + dj;
          rim = i2 >= 0 && j2 >= 0 && i2 < t.nx && j2 < t.ny &&
                ring[static_cast<std::size_t>(i2) * t.ny + j2] == -1;
        }
      if (rim) front.push_back(q);
    }
  // The first ring continues its neighbours' facets (so a raster cell that straddles the rim
  // interpolates planes no steeper than the patch's); later rings take the mean of their 8
  // neighbours from earlier rings.
  std::vector<std::size_t> next;
  for (int k = 1; !front.empty(); ++k) {
    next.clear();
    for (std::size_t q : front) {
      const int i = static_cast<int>(q / t.ny), j = static_cast<int>(q % t.ny);
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int i2 = i + di, j2 = j + dj;
          if (i2 < 0 || j2 < 0 || i2 >= t.nx || j2 >= t.ny) continue;
          const std::size_t q2 = static_cast<std::size_t>(i2) * t.ny + j2;
          if (ring[q2] == -1) ring[q2] = k, next.push_back(q2);
        }
    }
    for (std::size_t q : next) {
      const int i = static_cast<int>(q / t.ny), j = static_cast<int>(q % t.ny);
      const double x = t.origin.x() + i * t.cell, y = t.origin.y() + j * t.cell;
      double sum = 0, lo = -1e300, hi = 1e300;
      int cnt = 0;
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int i2 = i + di, j2 = j + dj;
          if (i2 < 0 || j2 < 0 || i2 >= t.nx || j2 >= t.ny) continue;
          const std::size_t q2 = static_cast<std::size_t>(i2) * t.ny + j2;
          if (ring[q2] < 0 || ring[q2] >= k) continue;
          sum += k == 1 ? std::clamp(Facet(mesh, face[q2]).z(x, y), h_lo, h_hi) : mz[q2];
          const double reach = max_slope * t.cell * ((di != 0 && dj != 0) ? M_SQRT2 : 1.0);
          lo = std::max(lo, mz[q2] - reach), hi = std::min(hi, mz[q2] + reach);
          ++cnt;
        }
      // Past the first ring, no steeper than max_slope from any earlier neighbour (where
      // they disagree by more, the middle of the two bounds).
      const double h = sum / cnt;
      mz[q] = k == 1 ? h : lo <= hi ? std::clamp(h, lo, hi) : 0.5 * (lo + hi);
    }
    front.swap(next);
  }
  // Rings from different stretches of the rim meet in ridges: relax H off the patch towards
  // the mean of its neighbours (the patch and the first ring stay).
  for (int sweep = 0; sweep < 20; ++sweep) relax(mz, ring, t.nx, t.ny);
  t.h_lo = h_lo, t.h_hi = h_hi;
  t.h = std::move(mz);
  return t;
}

FacetSamples facet_samples(const TriangleMesh& mesh, const Patch& patch,
                           const std::vector<Vec2>& xy, const std::vector<char>& want) {
  FacetSamples out;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  out.h.assign(xy.size(), nan);
  out.slope.assign(xy.size(), Vec2(nan, nan));
  height_range(mesh, patch, &out.h_lo, &out.h_hi);
  if (patch.faces.empty()) return out;
  // Triangles binned by their XY boxes on buckets of about four triangles' size.
  const Vec2 lo = patch.xy_min, ext = (patch.xy_max - patch.xy_min).cwiseMax(Vec2(1e-6, 1e-6));
  const double b =
      std::max(0.5, 2 * std::sqrt(ext.x() * ext.y() / static_cast<double>(patch.faces.size())));
  const int bx = static_cast<int>(ext.x() / b) + 1, by = static_cast<int>(ext.y() / b) + 1;
  std::vector<std::vector<int>> bucket(static_cast<std::size_t>(bx) * by);
  const auto clampi = [](double v, int n) { return std::clamp(static_cast<int>(v), 0, n - 1); };
  for (int f : patch.faces) {
    const Facet t3(mesh, f);
    const Vec2 f_lo = (t3.xy_min() - lo) / b, f_hi = (t3.xy_max() - lo) / b;
    const int i0 = clampi(f_lo.x(), bx), i1 = clampi(f_hi.x(), bx);
    const int j0 = clampi(f_lo.y(), by), j1 = clampi(f_hi.y(), by);
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) bucket[static_cast<std::size_t>(i) * by + j].push_back(f);
  }
  // Each point on its own, side by side (a start's one patch left the other core idle).
  core::parallel_for(std::size_t{0}, xy.size(), [&](std::size_t k) {
    if (!want[k]) return;
    const double x = xy[k].x(), y = xy[k].y();
    if (x < lo.x() - b || y < lo.y() - b || x > lo.x() + ext.x() + b || y > lo.y() + ext.y() + b)
      return;  // no triangle near
    const int ci = clampi((x - lo.x()) / b, bx), cj = clampi((y - lo.y()) / b, by);
    double best = -std::numeric_limits<double>::infinity(), near_d = 1e300;
    int inside = -1, nearest = -1;
    for (int i = std::max(0, ci - 1); i <= std::min(bx - 1, ci + 1); ++i)
      for (int j = std::max(0, cj - 1); j <= std::min(by - 1, cj + 1); ++j)
        for (int f : bucket[static_cast<std::size_t>(i) * by + j]) {
          const Facet t3(mesh, f);
          if (t3.d == 0) continue;
          if (t3.covers(x, y)) {
            const double z = t3.z(x, y);
            if (z > best) best = z, inside = f;
            continue;
          }
          const Vec2 g = (t3.a + t3.b + t3.c).head<2>() / 3.0 - xy[k];
          if (g.squaredNorm() < near_d) near_d = g.squaredNorm(), nearest = f;
        }
    const int f = inside >= 0 ? inside : nearest;
    if (f < 0) return;
    const Facet t3(mesh, f);
    out.slope[k] = t3.slope();
    out.h[k] = t3.a.z() + out.slope[k].dot(xy[k] - t3.a.head<2>());
  });
  return out;
}

}  // namespace nonplanar::layers
