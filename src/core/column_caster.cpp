#include "core/column_caster.hpp"

#include <algorithm>
#include <cmath>

namespace nonplanar {

ColumnCaster::ColumnCaster(const TriangleMesh& mesh, double cell) : mesh_(mesh), cell_(cell) {
  const BoundingBox b = bounding_box(mesh);
  origin_ = b.min.head<2>();
  const Vec2 size = b.size().head<2>();
  // Keep the grid to at most ~1M bins whatever the part's size.
  cell_ = std::max({cell, size.x() / 1000.0, size.y() / 1000.0, 1e-6});
  nx_ = static_cast<int>(size.x() / cell_) + 1;
  ny_ = static_cast<int>(size.y() / cell_) + 1;
  bins_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
    for (int v : mesh.faces[f]) {
      lo = lo.cwiseMin(mesh.vertices[v].head<2>());
      hi = hi.cwiseMax(mesh.vertices[v].head<2>());
    }
    const int i0 = static_cast<int>((lo.x() - origin_.x()) / cell_);
    const int i1 = static_cast<int>((hi.x() - origin_.x()) / cell_);
    const int j0 = static_cast<int>((lo.y() - origin_.y()) / cell_);
    const int j1 = static_cast<int>((hi.y() - origin_.y()) / cell_);
    for (int i = std::max(i0, 0); i <= std::min(i1, nx_ - 1); ++i)
      for (int j = std::max(j0, 0); j <= std::min(j1, ny_ - 1); ++j)
        bins_[static_cast<std::size_t>(i) * ny_ + j].push_back(static_cast<int>(f));
  }
}

std::vector<double> ColumnCaster::crossings(double x, double y) const {
  std::vector<double> z;
  const int i = static_cast<int>(std::floor((x - origin_.x()) / cell_));
  const int j = static_cast<int>(std::floor((y - origin_.y()) / cell_));
  if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return z;
  for (int f : bins_[static_cast<std::size_t>(i) * ny_ + j]) {
    const auto& t = mesh_.faces[f];
    const Vec3 &a = mesh_.vertices[t[0]], &b = mesh_.vertices[t[1]], &c = mesh_.vertices[t[2]];
    // Barycentric coordinates in XY, with a little slack so a line through a shared edge
    // or vertex is claimed by every face there (rounding must not drop it); the copies
    // have the same height and are merged below.
    const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
    if (d == 0.0) continue;  // vertical triangle: the line grazes it
    const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
    const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
    const double l0 = 1.0 - l1 - l2;
    auto in = [](double l) { return l >= -1e-12; };
    if (!(in(l0) && in(l1) && in(l2))) continue;
    z.push_back(l0 * a.z() + l1 * b.z() + l2 * c.z());
  }
  std::sort(z.begin(), z.end());
  // Merge crossings at the same height (a line through a shared edge hits both faces).
  z.erase(
      std::unique(z.begin(), z.end(), [](double p, double q) { return std::abs(p - q) < 1e-9; }),
      z.end());
  return z;
}

std::vector<std::pair<double, double>> ColumnCaster::intervals(double x, double y) const {
  const std::vector<double> z = crossings(x, y);
  std::vector<std::pair<double, double>> out;
  for (std::size_t k = 0; k + 1 < z.size(); k += 2) out.emplace_back(z[k], z[k + 1]);
  return out;
}

bool ColumnCaster::inside(double x, double y, double z) const {
  for (const auto& [lo, hi] : intervals(x, y))
    if (z >= lo && z <= hi) return true;
  return false;
}

}  // namespace nonplanar
