#include "deform/gate_zones.hpp"

#include <algorithm>

namespace nonplanar {

namespace {

BoundingBox box_of(const ExtrusionPath& p) {
  BoundingBox b;
  for (const Vec3& v : p.points) b.extend(v);
  return b;
}

bool meet(const BoundingBox& a, const BoundingBox& b) {
  return (a.max.array() >= b.min.array()).all() && (a.min.array() <= b.max.array()).all();
}

bool inside(const Vec3& p, const BoundingBox& b) {
  return (p.array() >= b.min.array()).all() && (p.array() <= b.max.array()).all();
}

}  // namespace

void GateZones::find_last_layers(const std::vector<LayerToolpaths>& layers) {
  last_layer.assign(query.size(), -1);
  for (std::size_t li = 0; li < layers.size(); ++li)
    for (const ExtrusionPath& p : layers[li].paths) {
      const BoundingBox pb = box_of(p);
      for (std::size_t b = 0; b < query.size(); ++b) {
        if (last_layer[b] >= static_cast<int>(li) || !meet(pb, query[b])) continue;
        for (const Vec3& v : p.points)
          if (inside(v, query[b])) {
            last_layer[b] = static_cast<int>(li);
            break;
          }
      }
    }
}

bool GateZones::may_matter(const ExtrusionPath& p, int layer) const {
  const BoundingBox pb = box_of(p);
  for (std::size_t b = 0; b < material.size(); ++b)
    if ((b >= last_layer.size() || layer <= last_layer[b]) && meet(pb, material[b])) return true;
  return false;
}

GateZones gate_zones(const layers::BandedField& field, double R) {
  GateZones g;
  for (const layers::Band& b : field.bands()) {
    const double cell = b.blend_cell;
    // β vanishes two cells past its raster (the support of its cubic B-spline); one more
    // cell of margin.
    const Vec2 lo = b.blend_origin - Vec2(3 * cell, 3 * cell);
    const Vec2 hi = b.blend_origin + Vec2((b.blend_nx + 2) * cell, (b.blend_ny + 2) * cell);
    // The top's highest point over the support, sampled at the raster's nodes (between
    // them a smooth surface rises by far less than the 1 mm of slack).
    double top = b.c;
    for (int i = 0; i <= b.blend_nx + 5; ++i)
      for (int j = 0; j <= b.blend_ny + 5; ++j)
        top = std::max(top, b.surface(b.basis(lo.x() + i * cell, lo.y() + j * cell), 0));
    const double z0 = b.c - 1.0, z1 = top + b.fade + 1.0;
    g.query.push_back({{lo.x() - R - 1, lo.y() - R - 1, z0}, {hi.x() + R + 1, hi.y() + R + 1, z1}});
    g.material.push_back({{lo.x() - 2 * R - 1, lo.y() - 2 * R - 1, z0},
                          {hi.x() + 2 * R + 1, hi.y() + 2 * R + 1, 1e300}});
  }
  return g;
}

}  // namespace nonplanar
