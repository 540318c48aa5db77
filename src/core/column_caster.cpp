#include "core/column_caster.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

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

namespace {

// Where face f meets the vertical line at (x, y): its height, and +1 entering / −1 leaving.
std::optional<std::pair<double, int>> hit(const TriangleMesh& m, int f, double x, double y) {
  const auto& t = m.faces[static_cast<std::size_t>(f)];
  const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
  // Barycentric coordinates in XY, with a little slack so a line through a shared edge
  // or vertex is claimed by every face there (rounding must not drop it).
  const double d = (b.x() - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (b.y() - a.y());
  if (d == 0.0) return std::nullopt;  // vertical triangle: the line grazes it
  const double l1 = ((x - a.x()) * (c.y() - a.y()) - (c.x() - a.x()) * (y - a.y())) / d;
  const double l2 = ((b.x() - a.x()) * (y - a.y()) - (x - a.x()) * (b.y() - a.y())) / d;
  const double l0 = 1.0 - l1 - l2;
  if (l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12) return std::nullopt;
  return std::pair(l0 * a.z() + l1 * b.z() + l2 * c.z(), d > 0 ? -1 : +1);  // d > 0: normal up
}

// (height, +1 entering / −1 leaving) of every face the vertical line at (x, y) meets.
std::vector<std::pair<double, int>> signed_hits(const TriangleMesh& m,
                                                const std::vector<int>& faces, double x, double y) {
  std::vector<std::pair<double, int>> hits;
  // Copies with the same height and direction (a shared edge's faces) are merged below.
  for (int f : faces)
    if (const auto h = hit(m, f, x, y)) hits.push_back(*h);
  // Entering before leaving at equal heights, so touching shells stay one interval.
  std::sort(hits.begin(), hits.end(), [](const auto& p, const auto& q) {
    return p.first < q.first - 1e-9 || (std::abs(p.first - q.first) <= 1e-9 && p.second > q.second);
  });
  hits.erase(std::unique(hits.begin(), hits.end(),
                         [](const auto& p, const auto& q) {
                           return std::abs(p.first - q.first) < 1e-9 && p.second == q.second;
                         }),
             hits.end());
  return hits;
}

}  // namespace

std::vector<std::pair<double, int>> ColumnCaster::face_hits(double x, double y) const {
  std::vector<std::pair<double, int>> out;
  const int i = static_cast<int>(std::floor((x - origin_.x()) / cell_));
  const int j = static_cast<int>(std::floor((y - origin_.y()) / cell_));
  if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return out;
  for (int f : bins_[static_cast<std::size_t>(i) * ny_ + j])
    if (const auto h = hit(mesh_, f, x, y)) out.emplace_back(h->first, f);
  return out;
}

std::vector<double> ColumnCaster::crossings(double x, double y) const {
  std::vector<double> z;
  const int i = static_cast<int>(std::floor((x - origin_.x()) / cell_));
  const int j = static_cast<int>(std::floor((y - origin_.y()) / cell_));
  if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return z;
  for (const auto& h : signed_hits(mesh_, bins_[static_cast<std::size_t>(i) * ny_ + j], x, y))
    z.push_back(h.first);
  return z;
}

std::vector<std::pair<double, double>> ColumnCaster::intervals(double x, double y) const {
  std::vector<std::pair<double, double>> out;
  const int i = static_cast<int>(std::floor((x - origin_.x()) / cell_));
  const int j = static_cast<int>(std::floor((y - origin_.y()) / cell_));
  if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return out;
  int winding = 0;
  double start = 0;
  for (const auto& [z, s] :
       signed_hits(mesh_, bins_[static_cast<std::size_t>(i) * ny_ + j], x, y)) {
    const int before = winding;
    winding += s;
    if (before <= 0 && winding > 0) start = z;
    if (before > 0 && winding <= 0) out.emplace_back(start, z);
  }
  return out;
}

bool ColumnCaster::inside(double x, double y, double z) const {
  for (const auto& [lo, hi] : intervals(x, y))
    if (z >= lo && z <= hi) return true;
  return false;
}

}  // namespace nonplanar
