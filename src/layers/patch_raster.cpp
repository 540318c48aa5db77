#include "layers/patch_raster.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nonplanar::layers {
namespace {

// 1D squared distance transform of f (Felzenszwalb & Huttenlocher 2012).
void dt1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v,
          std::vector<double>& z) {
  const int n = static_cast<int>(f.size());
  const double inf = std::numeric_limits<double>::infinity();
  int k = 0;
  v[0] = 0;
  z[0] = -inf;
  z[1] = inf;
  for (int q = 1; q < n; ++q) {
    if (f[q] == inf) continue;
    if (f[v[k]] == inf) {
      v[k] = q;
      continue;
    }
    double s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    while (k > 0 && s <= z[k]) {
      --k;
      s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = inf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    d[q] = f[v[k]] == inf ? inf : (q - v[k]) * (q - v[k]) + f[v[k]];
  }
}

}  // namespace

double PatchRaster::distance(double x, double y) const {
  const int i = static_cast<int>(std::lround((x - origin.x()) / cell));
  const int j = static_cast<int>(std::lround((y - origin.y()) / cell));
  if (i < 0 || j < 0 || i >= nx || j >= ny) return 1e300;
  return dist[at(i, j)];
}

PatchRaster rasterize_patch(const TriangleMesh& mesh, const Patch& patch, double cell, double pad) {
  PatchRaster r;
  r.cell = cell;
  r.origin = patch.xy_min - Vec2(pad, pad);
  const Vec2 size = patch.xy_max - patch.xy_min + Vec2(2 * pad, 2 * pad);
  r.nx = static_cast<int>(std::ceil(size.x() / cell)) + 1;
  r.ny = static_cast<int>(std::ceil(size.y() / cell)) + 1;
  r.mask.assign(static_cast<std::size_t>(r.nx) * r.ny, 0);
  for (int f : patch.faces) {
    const auto& t = mesh.faces[f];
    const Vec2 a = mesh.vertices[t[0]].head<2>(), b = mesh.vertices[t[1]].head<2>(),
               c = mesh.vertices[t[2]].head<2>();
    const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (d == 0) continue;
    const Vec2 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    const int i0 = std::max(0, static_cast<int>(std::ceil((lo.x() - r.origin.x()) / cell)));
    const int i1 = std::min(r.nx - 1, static_cast<int>(std::floor((hi.x() - r.origin.x()) / cell)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((lo.y() - r.origin.y()) / cell)));
    const int j1 = std::min(r.ny - 1, static_cast<int>(std::floor((hi.y() - r.origin.y()) / cell)));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) {
        const double x = r.origin.x() + i * cell, y = r.origin.y() + j * cell;
        const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
        const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
        if (l1 >= -1e-9 && l2 >= -1e-9 && l1 + l2 <= 1 + 1e-9) r.mask[r.at(i, j)] = 1;
      }
  }
  // Squared distance in cells: columns, then rows.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> g(r.mask.size());
  for (std::size_t k = 0; k < g.size(); ++k) g[k] = r.mask[k] ? 0.0 : inf;
  const int n = std::max(r.nx, r.ny);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (int i = 0; i < r.nx; ++i) {
    f.assign(r.ny, 0), d.assign(r.ny, 0);
    for (int j = 0; j < r.ny; ++j) f[j] = g[r.at(i, j)];
    dt1d(f, d, v, z);
    for (int j = 0; j < r.ny; ++j) g[r.at(i, j)] = d[j];
  }
  for (int j = 0; j < r.ny; ++j) {
    f.assign(r.nx, 0), d.assign(r.nx, 0);
    for (int i = 0; i < r.nx; ++i) f[i] = g[r.at(i, j)];
    dt1d(f, d, v, z);
    for (int i = 0; i < r.nx; ++i) g[r.at(i, j)] = d[i];
  }
  r.dist.resize(g.size());
  for (std::size_t k = 0; k < g.size(); ++k)
    r.dist[k] = g[k] == inf ? 1e300 : std::sqrt(g[k]) * cell;
  return r;
}

}  // namespace nonplanar::layers
