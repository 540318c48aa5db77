#include "layers/faceted_top.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nonplanar::layers {
namespace {

// The raster cell around (x, y): its first node and the fractions (u, v) across it. H is
// constant past the raster's edge.
struct Cell {
  const double* p;
  double u, v;
};
Cell locate(const FacetedTop& t, double x, double y) {
  const double fx = std::clamp((x - t.origin.x()) / t.cell, 0.0, t.nx - 1.0);
  const double fy = std::clamp((y - t.origin.y()) / t.cell, 0.0, t.ny - 1.0);
  const int i = std::clamp(static_cast<int>(std::floor(fx)), 0, t.nx - 2);
  const int j = std::clamp(static_cast<int>(std::floor(fy)), 0, t.ny - 2);
  return {&t.h[static_cast<std::size_t>(i) * t.ny + j], fx - i, fy - j};
}

}  // namespace

double FacetedTop::height(double x, double y) const {
  const auto [p, u, v] = locate(*this, x, y);
  return (1 - u) * ((1 - v) * p[0] + v * p[1]) + u * ((1 - v) * p[ny] + v * p[ny + 1]);
}

Vec2 FacetedTop::gradient(double x, double y) const {
  const auto [p, u, v] = locate(*this, x, y);
  return {((1 - v) * (p[ny] - p[0]) + v * (p[ny + 1] - p[1])) / cell,
          ((1 - u) * (p[1] - p[0]) + u * (p[ny + 1] - p[ny])) / cell};
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
  std::vector<double> mz(n, lowest);
  std::vector<int> face(n, -1);  ///< the triangle that gave mz
  // The triangles' heights at the nodes inside them (the highest where two overlap in XY).
  for (int f : patch.faces) {
    const auto& tri = mesh.faces[f];
    const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (d == 0) continue;
    const double x_lo = std::min({a.x(), b.x(), c.x()}), x_hi = std::max({a.x(), b.x(), c.x()});
    const double y_lo = std::min({a.y(), b.y(), c.y()}), y_hi = std::max({a.y(), b.y(), c.y()});
    const int i0 = std::max(0, static_cast<int>(std::ceil((x_lo - t.origin.x()) / t.cell)));
    const int i1 = std::min(t.nx - 1, static_cast<int>(std::floor((x_hi - t.origin.x()) / t.cell)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((y_lo - t.origin.y()) / t.cell)));
    const int j1 = std::min(t.ny - 1, static_cast<int>(std::floor((y_hi - t.origin.y()) / t.cell)));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const double x = t.origin.x() + i * t.cell, y = t.origin.y() + j * t.cell;
        // Barycentric coordinates of b (l1) and c (l2).
        const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
        const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
        if (l1 < -1e-9 || l2 < -1e-9 || l1 + l2 > 1 + 1e-9) continue;
        const double z = a.z() + l1 * (b.z() - a.z()) + l2 * (c.z() - a.z());
        const std::size_t q = static_cast<std::size_t>(i) * t.ny + j;
        if (z > mz[q]) mz[q] = z, face[q] = f;
      }
  }
  // H: the triangles' heights (ring 0), then carried outward ring by ring.
  std::vector<int> ring(n, -1);
  std::vector<std::size_t> front;
  // The patch's height range, from its vertices (so it does not depend on the raster).
  double h_lo = std::numeric_limits<double>::infinity(), h_hi = -h_lo;
  for (int f : patch.faces)
    for (int v : mesh.faces[f]) {
      h_lo = std::min(h_lo, mesh.vertices[v].z());
      h_hi = std::max(h_hi, mesh.vertices[v].z());
    }
  for (std::size_t k = 0; k < n; ++k)
    if (mz[k] > lowest) {
      ring[k] = 0;
      front.push_back(k);
    }
  if (front.empty()) return {};  // no node falls inside the patch: the caller keeps the fit
  // The plane of triangle f at (x, y), extrapolated.
  const auto plane = [&](int f, double x, double y) {
    const auto& tri = mesh.faces[f];
    const Vec3 &a = mesh.vertices[tri[0]], &b = mesh.vertices[tri[1]], &c = mesh.vertices[tri[2]];
    const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
    const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
    return a.z() + l1 * (b.z() - a.z()) + l2 * (c.z() - a.z());
  };
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
          sum += k == 1 ? std::clamp(plane(face[q2], x, y), h_lo, h_hi) : mz[q2];
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
  for (int sweep = 0; sweep < 20; ++sweep)
    for (int i = 1; i + 1 < t.nx; ++i)
      for (int j = 1; j + 1 < t.ny; ++j) {
        const std::size_t q = static_cast<std::size_t>(i) * t.ny + j;
        if (ring[q] < 2) continue;
        mz[q] = 0.25 * (mz[q - t.ny] + mz[q + t.ny] + mz[q - 1] + mz[q + 1]);
      }
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
  out.h_lo = std::numeric_limits<double>::infinity(), out.h_hi = -out.h_lo;
  for (int f : patch.faces)
    for (int v : mesh.faces[f]) {
      out.h_lo = std::min(out.h_lo, mesh.vertices[v].z());
      out.h_hi = std::max(out.h_hi, mesh.vertices[v].z());
    }
  if (patch.faces.empty()) return out;
  // Triangles binned by their XY boxes on buckets of about four triangles' size.
  const Vec2 lo = patch.xy_min, ext = (patch.xy_max - patch.xy_min).cwiseMax(Vec2(1e-6, 1e-6));
  const double b =
      std::max(0.5, 2 * std::sqrt(ext.x() * ext.y() / static_cast<double>(patch.faces.size())));
  const int bx = static_cast<int>(ext.x() / b) + 1, by = static_cast<int>(ext.y() / b) + 1;
  std::vector<std::vector<int>> bucket(static_cast<std::size_t>(bx) * by);
  const auto clampi = [](double v, int n) { return std::clamp(static_cast<int>(v), 0, n - 1); };
  for (int f : patch.faces) {
    const auto& t = mesh.faces[f];
    const Vec3 &a = mesh.vertices[t[0]], &c1 = mesh.vertices[t[1]], &c2 = mesh.vertices[t[2]];
    const int i0 = clampi((std::min({a.x(), c1.x(), c2.x()}) - lo.x()) / b, bx);
    const int i1 = clampi((std::max({a.x(), c1.x(), c2.x()}) - lo.x()) / b, bx);
    const int j0 = clampi((std::min({a.y(), c1.y(), c2.y()}) - lo.y()) / b, by);
    const int j1 = clampi((std::max({a.y(), c1.y(), c2.y()}) - lo.y()) / b, by);
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) bucket[static_cast<std::size_t>(i) * by + j].push_back(f);
  }
  for (std::size_t k = 0; k < xy.size(); ++k) {
    if (!want[k]) continue;
    const double x = xy[k].x(), y = xy[k].y();
    if (x < lo.x() - b || y < lo.y() - b || x > lo.x() + ext.x() + b || y > lo.y() + ext.y() + b)
      continue;  // no triangle near
    const int ci = clampi((x - lo.x()) / b, bx), cj = clampi((y - lo.y()) / b, by);
    double best = -std::numeric_limits<double>::infinity(), near_d = 1e300;
    int inside = -1, nearest = -1;
    for (int i = std::max(0, ci - 1); i <= std::min(bx - 1, ci + 1); ++i)
      for (int j = std::max(0, cj - 1); j <= std::min(by - 1, cj + 1); ++j)
        for (int f : bucket[static_cast<std::size_t>(i) * by + j]) {
          const auto& t = mesh.faces[f];
          const Vec3 &a = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]], &p2 = mesh.vertices[t[2]];
          const double d =
              (p1.x() - a.x()) * (p2.y() - a.y()) - (p2.x() - a.x()) * (p1.y() - a.y());
          if (d == 0) continue;
          const double l1 = ((x - a.x()) * (p2.y() - a.y()) - (p2.x() - a.x()) * (y - a.y())) / d;
          const double l2 = ((p1.x() - a.x()) * (y - a.y()) - (x - a.x()) * (p1.y() - a.y())) / d;
          const double z = a.z() + l1 * (p1.z() - a.z()) + l2 * (p2.z() - a.z());
          if (l1 >= -1e-9 && l2 >= -1e-9 && l1 + l2 <= 1 + 1e-9) {
            if (z > best) best = z, inside = f;
            continue;
          }
          const Vec2 g = (a + p1 + p2).head<2>() / 3.0 - xy[k];
          if (g.squaredNorm() < near_d) near_d = g.squaredNorm(), nearest = f;
        }
    const int f = inside >= 0 ? inside : nearest;
    if (f < 0) continue;
    const auto& t = mesh.faces[f];
    const Vec3 &a = mesh.vertices[t[0]], &p1 = mesh.vertices[t[1]], &p2 = mesh.vertices[t[2]];
    const Vec3 nrm = (p1 - a).cross(p2 - a);
    out.slope[k] = Vec2(-nrm.x() / nrm.z(), -nrm.y() / nrm.z());
    out.h[k] = a.z() + out.slope[k].dot(xy[k] - a.head<2>());
  }
  return out;
}

}  // namespace nonplanar::layers
