#include <algorithm>
#include <cmath>

#include "nonplanar/program.hpp"

namespace nonplanar {
namespace {

// How far p lies outside the box in XY (0 inside), mm.
double xy_gap(const BoundingBox& b, const Vec3& p) {
  const double dx = std::max({b.min.x() - p.x(), 0.0, p.x() - b.max.x()});
  const double dy = std::max({b.min.y() - p.y(), 0.0, p.y() - b.max.y()});
  return std::hypot(dx, dy);
}

bool xy_overlap(const BoundingBox& a, const BoundingBox& b) {
  return a.min.x() <= b.max.x() && b.min.x() <= a.max.x() && a.min.y() <= b.max.y() &&
         b.min.y() <= a.max.y();
}

// Sets the cells whose centres lie within `grow` mm of the triangle's XY shadow (inside all
// three edges' lines moved out by `grow`: a little more near sharp corners, never less).
void shade(ObjectOutline& o, const Vec2& a, const Vec2& b, const Vec2& c, double grow) {
  const double twice = (b - a).x() * (c - a).y() - (c - a).x() * (b - a).y();
  if (twice == 0) return;
  const Vec2 v[3] = {a, twice > 0 ? b : c, twice > 0 ? c : b};  // counter-clockwise
  const Vec2 lo = a.cwiseMin(b).cwiseMin(c) - Vec2(grow, grow);
  const Vec2 hi = a.cwiseMax(b).cwiseMax(c) + Vec2(grow, grow);
  const int i0 = std::max(0, static_cast<int>(std::floor((lo.x() - o.origin.x()) / o.cell)));
  const int i1 = std::min(o.nx - 1, static_cast<int>(std::floor((hi.x() - o.origin.x()) / o.cell)));
  const int j0 = std::max(0, static_cast<int>(std::floor((lo.y() - o.origin.y()) / o.cell)));
  const int j1 = std::min(o.ny - 1, static_cast<int>(std::floor((hi.y() - o.origin.y()) / o.cell)));
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const Vec2 p = o.origin + Vec2(i + 0.5, j + 0.5) * o.cell;
      bool in = true;
      for (int e = 0; e < 3 && in; ++e) {
        const Vec2 d = v[(e + 1) % 3] - v[e];
        in = (d.x() * (p - v[e]).y() - d.y() * (p - v[e]).x()) >= -grow * d.norm();
      }
      if (in) o.shadow[static_cast<std::size_t>(i) * o.ny + j] = 1;
    }
}

}  // namespace

bool ObjectOutline::covers(const Vec2& p) const {
  if (shadow.empty())
    return p.x() >= box.min.x() && p.x() <= box.max.x() && p.y() >= box.min.y() &&
           p.y() <= box.max.y();
  const auto i = static_cast<int>(std::floor((p.x() - origin.x()) / cell));
  const auto j = static_cast<int>(std::floor((p.y() - origin.y()) / cell));
  return i >= 0 && j >= 0 && i < nx && j < ny && shadow[static_cast<std::size_t>(i) * ny + j];
}

std::vector<ObjectOutline> object_outlines(const TriangleMesh& mesh, const PlateObjects& objects) {
  if (!objects.several() || objects.items.size() > kMostPlateObjects ||
      objects.face.size() != mesh.faces.size())
    return {};
  std::vector<ObjectOutline> out(objects.items.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto k = static_cast<std::size_t>(objects.face[f]);
    if (k < out.size())
      for (int v : mesh.faces[f]) out[k].box.extend(mesh.vertices[static_cast<std::size_t>(v)]);
  }
  // Rasters only where boxes overlap: apart, the box says whose a point is.
  std::vector<char> crowded(out.size(), 0);
  for (std::size_t a = 0; a < out.size(); ++a)
    for (std::size_t b = a + 1; b < out.size(); ++b)
      if (!out[a].box.empty() && !out[b].box.empty() && xy_overlap(out[a].box, out[b].box))
        crowded[a] = crowded[b] = 1;
  for (std::size_t k = 0; k < out.size(); ++k) {
    ObjectOutline& o = out[k];
    if (!crowded[k]) continue;
    const Vec2 size = (o.box.max - o.box.min).head<2>();
    o.cell = std::max(0.2, std::sqrt(size.x() * size.y() / 4e6));
    o.origin = o.box.min.head<2>() - Vec2(o.cell, o.cell);
    o.nx = static_cast<int>(std::ceil(size.x() / o.cell)) + 2;
    o.ny = static_cast<int>(std::ceil(size.y() / o.cell)) + 2;
    o.shadow.assign(static_cast<std::size_t>(o.nx) * o.ny, 0);
  }
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto k = static_cast<std::size_t>(objects.face[f]);
    if (k >= out.size() || out[k].shadow.empty()) continue;
    const auto& t = mesh.faces[f];
    auto xy = [&](int c) { return mesh.vertices[static_cast<std::size_t>(t[c])].head<2>(); };
    shade(out[k], xy(0), xy(1), xy(2), out[k].cell * M_SQRT1_2);
  }
  return out;
}

int object_at(const std::vector<ObjectOutline>& outlines, const Vec3& p) {
  int best = 0;
  double best_gap = 1e300;
  int in_boxes = 0;
  for (std::size_t k = 0; k < outlines.size(); ++k) {
    const double gap = xy_gap(outlines[k].box, p);
    in_boxes += gap == 0;
    if (gap < best_gap) best_gap = gap, best = static_cast<int>(k);
  }
  if (in_boxes < 2) return best;
  // Boxes overlap here (objects side by side, one under another's overhang): the shadow
  // decides, and among shadows the box nearest in z.
  double best_dz = 1e300;
  for (std::size_t k = 0; k < outlines.size(); ++k) {
    const ObjectOutline& o = outlines[k];
    if (xy_gap(o.box, p) > 0 || !o.covers(p.head<2>())) continue;
    const double dz = std::max({o.box.min.z() - p.z(), 0.0, p.z() - o.box.max.z()});
    if (dz < best_dz) best_dz = dz, best = static_cast<int>(k);
  }
  return best;
}

void group_by_object(std::vector<LayerToolpaths>& layers,
                     const std::vector<ObjectOutline>& outlines) {
  if (outlines.size() < 2) return;
  for (LayerToolpaths& L : layers) {
    for (ExtrusionPath& p : L.paths)
      if (p.role != ExtrusionRole::skirt && !p.points.empty())
        p.object = object_at(outlines, p.points[p.points.size() / 2]);
    std::stable_sort(L.paths.begin(), L.paths.end(),
                     [](const ExtrusionPath& a, const ExtrusionPath& b) {
                       const bool sa = a.role == ExtrusionRole::skirt;
                       const bool sb = b.role == ExtrusionRole::skirt;
                       if (sa != sb) return sa;
                       return !sa && a.object < b.object;
                     });
  }
}

}  // namespace nonplanar
