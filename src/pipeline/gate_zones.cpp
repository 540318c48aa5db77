#include "pipeline/gate_zones.hpp"

#include <algorithm>

namespace nonplanar {

namespace {

BoundingBox box_of(const ExtrusionPath& p) {
  BoundingBox b;
  for (const Vec3& v : p.points) b.extend(v);
  return b;
}

}  // namespace

void GateZones::find_last_layers(const std::vector<LayerToolpaths>& layers) {
  last_layer.assign(query.size(), -1);
  for (std::size_t li = 0; li < layers.size(); ++li)
    for (const ExtrusionPath& p : layers[li].paths) {
      const BoundingBox pb = box_of(p);
      for (std::size_t b = 0; b < query.size(); ++b) {
        if (last_layer[b] >= static_cast<int>(li) || !pb.intersects(query[b])) continue;
        for (const Vec3& v : p.points)
          if (query[b].contains(v)) {
            last_layer[b] = static_cast<int>(li);
            break;
          }
      }
    }
}

bool GateZones::may_matter(const GcodeMove& m, int layer) const {
  const BoundingBox mb{m.from.cwiseMin(m.to), m.from.cwiseMax(m.to)};
  for (std::size_t b = 0; b < material.size(); ++b)
    if ((b >= last_layer.size() || layer <= last_layer[b]) && mb.intersects(material[b]))
      return true;
  return false;
}

GateZones gate_zones(const layers::BandedField& field, double R) {
  GateZones g;
  for (std::size_t n = 0; n < field.bands().size(); ++n) {
    const layers::BandedField::Reach& r = field.reach()[n];
    const double z0 = field.bands()[n].c - 1.0;
    g.query.push_back(
        {{r.lo.x() - R - 1, r.lo.y() - R - 1, z0}, {r.hi.x() + R + 1, r.hi.y() + R + 1, r.z_top}});
    g.material.push_back({{r.lo.x() - 2 * R - 1, r.lo.y() - 2 * R - 1, z0},
                          {r.hi.x() + 2 * R + 1, r.hi.y() + 2 * R + 1, 1e300}});
  }
  return g;
}

OutOfOrder out_of_order(const std::vector<LayerToolpaths>& layers) {
  // Between two path points z is linear, so a point between them is below the highest point
  // before it only if one of them is: their heights bound every sample's.
  OutOfOrder o;
  double highest = -1e300;
  for (std::size_t i = 0; i < layers.size(); ++i)
    for (const ExtrusionPath& p : layers[i].paths)
      for (const Vec3& v : p.points) {
        if (v.z() < highest)
          o.lo = std::min(o.lo, v.z()), o.hi = std::max(o.hi, v.z()),
          o.last_layer = static_cast<int>(i);
        highest = std::max(highest, v.z());
      }
  return o;
}

}  // namespace nonplanar
