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
  constexpr double kApart = 2.0;  // mm
  std::vector<OutOfOrder::Span> spans;
  double highest = -1e300;
  for (std::size_t i = 0; i < layers.size(); ++i)
    for (const ExtrusionPath& p : layers[i].paths)
      for (const Vec3& v : p.points) {
        if (v.z() < highest) {
          auto it = std::find_if(spans.begin(), spans.end(), [&](const OutOfOrder::Span& s) {
            return v.z() >= s.lo - kApart && v.z() <= s.hi + kApart;
          });
          if (it == spans.end()) it = spans.insert(spans.end(), OutOfOrder::Span{});
          it->lo = std::min(it->lo, v.z()), it->hi = std::max(it->hi, v.z());
          it->last_layer = static_cast<int>(i);
        }
        highest = std::max(highest, v.z());
      }
  // Spans that grew into each other: one.
  std::sort(spans.begin(), spans.end(),
            [](const OutOfOrder::Span& a, const OutOfOrder::Span& b) { return a.lo < b.lo; });
  OutOfOrder o;
  for (const OutOfOrder::Span& s : spans)
    if (!o.spans.empty() && s.lo <= o.spans.back().hi + kApart)
      o.spans.back().hi = std::max(o.spans.back().hi, s.hi),
      o.spans.back().last_layer = std::max(o.spans.back().last_layer, s.last_layer);
    else
      o.spans.push_back(s);
  return o;
}

bool OutOfOrder::looked_at(const Vec3& p) const {
  return std::any_of(spans.begin(), spans.end(),
                     [&](const Span& s) { return p.z() >= s.lo - 1 && p.z() <= s.hi + 1; });
}

bool OutOfOrder::may_matter(double z, int layer) const {
  return std::any_of(spans.begin(), spans.end(),
                     [&](const Span& s) { return layer <= s.last_layer && z >= s.lo - 1; });
}

}  // namespace nonplanar
