// The safety gate (DESIGN.md §3) on the paths about to be written, and the empty-print check.
#include "pipeline/gate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nonplanar/gcode.hpp"
#include "pipeline/gate_zones.hpp"

namespace nonplanar {

std::vector<PrintMove> moves_from_toolpaths(
    const std::vector<LayerToolpaths>& layers, const GcodeParams& g,
    const std::function<bool(const ExtrusionPath&, int)>& keep) {
  std::vector<PrintMove> out;
  std::size_t n = 0;
  for (const LayerToolpaths& L : layers)
    for (const ExtrusionPath& p : L.paths) n += p.points.size();
  out.reserve(n);
  Vec3 pos(0, 0, 0);
  for (std::size_t li = 0; li < layers.size(); ++li)
    for (const ExtrusionPath& p : layers[li].paths) {
      if (p.points.empty() || (keep && !keep(p, static_cast<int>(li)))) continue;
      PrintMove t;
      t.from = pos, t.to = p.points[0], t.layer = static_cast<int>(li), t.type = role_name(p.role);
      t.width = p.width;
      out.push_back(t);
      for (std::size_t k = 1; k < p.points.size(); ++k) {
        PrintMove m;
        m.from = p.points[k - 1], m.to = p.points[k];
        m.filament = (m.to - m.from).norm() *
                     filament_per_mm(p.width, 0.5 * (p.height[k] + p.height[k - 1]), g);
        m.extruding = m.filament > 0 && (m.to.head<2>() - m.from.head<2>()).norm() > 1e-9;
        m.type = role_name(p.role), m.layer = static_cast<int>(li), m.width = p.width;
        out.push_back(m);
      }
      pos = p.points.back();
    }
  return out;
}

// A part thinner than one extrusion, or an open sheet, slices to nothing: say so rather than
// write G-code that only draws a skirt (a lone sloped triangle once gave exit 0, a header
// claiming 274 core layers, and no extrusion).
std::optional<Error> nothing_to_print(const SliceResult& r, const TriangleMesh& mesh) {
  const bool prints = std::any_of(r.layers.begin(), r.layers.end(), [](const LayerToolpaths& L) {
    return std::any_of(L.paths.begin(), L.paths.end(), [](const ExtrusionPath& p) {
      return p.role != ExtrusionRole::skirt && p.points.size() >= 2;
    });
  });
  if (prints) return std::nullopt;
  const BoundingBox b = bounding_box(mesh);
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "nothing to print: the part (%.2f x %.2f x %.2f mm) holds no volume one "
                "extrusion can fill (smaller than a line, or an open surface)",
                b.size().x(), b.size().y(), b.size().z());
  return Error{Status::invalid_mesh, buf};
}

// Safety (DESIGN.md §3) on r.layers, rounded first to the µm they are written with (so
// `check` on the file agrees with this gate even for a point at the collision depth's edge):
// thickness and slope from the paths themselves, collisions with earlier layers from the
// independent check, looked for only near a band's curved layers when `banded` is given
// (gate_zones.hpp), everywhere else. Every breach goes to `violation`; false when it said stop.
// Fills r's figures.
Expected<bool> gate(SliceResult& r, const SliceJob& job, const layers::BandedField* banded,
                    const Violation& violation, const Context& ctx) {
  for (LayerToolpaths& layer : r.layers)
    for (ExtrusionPath& p : layer.paths)
      for (Vec3& v : p.points) v = (v * 1000.0).array().round() / 1000.0;
  const LayerParams& L = job.layers;
  r.thickness_min = 1e300, r.thickness_max = 0;
  const double tan_max = std::tan((L.max_angle_deg + 0.5) * M_PI / 180.0);
  for (std::size_t li = 0; li < r.layers.size(); ++li)
    for (const ExtrusionPath& p : r.layers[li].paths) {
      if (p.role == ExtrusionRole::skirt) continue;
      for (std::size_t k = 0; k < p.points.size(); ++k) {
        if (li > 0) {
          r.thickness_min = std::min(r.thickness_min, p.height[k]);
          r.thickness_max = std::max(r.thickness_max, p.height[k]);
          if ((p.height[k] < L.min_layer_height - 1e-3 ||
               p.height[k] > L.max_layer_height + 1e-3) &&
              !violation(p.points[k], "a layer leaves the thickness limits"))
            return false;
        }
        if (k == 0) continue;
        const double dxy = (p.points[k] - p.points[k - 1]).head<2>().norm();
        const double dz = std::abs(p.points[k].z() - p.points[k - 1].z());
        if (dxy > 0.05) r.steepest_deg = std::max(r.steepest_deg, std::atan2(dz, dxy) * 180 / M_PI);
        if (dxy > 0.05 && dz > tan_max * dxy &&
            !violation(p.points[k], "an extrusion is steeper than max_angle"))
          return false;
      }
    }
  if (r.thickness_min > r.thickness_max) r.thickness_min = r.thickness_max = 0;
  if (!r.nonplanar) return true;  // planar layers cannot dig into earlier ones
  // Collisions are looked for even when bands already broke a limit, so one retry drops
  // every offender (each retry replans, reslices and rechecks the whole part).
  CheckParams cp = job.check;
  // Only where a curved layer is within the head's reach (gate_zones.hpp): on the bunny that
  // skipped most of 24 million extrusion samples.
  GateZones zones = banded ? gate_zones(*banded, cp.toolhead.reach()) : GateZones{};
  zones.find_last_layers(r.layers);
  std::function<bool(const Vec3&)> looked_at;
  if (!zones.query.empty())
    looked_at = [&](const Vec3& p) {
      return std::any_of(zones.query.begin(), zones.query.end(),
                         [&](const BoundingBox& b) { return b.contains(p); });
    };
  auto figures = find_collisions(moves_from_toolpaths(r.layers, job.print.gcode,
                                                      [&](const ExtrusionPath& p, int li) {
                                                        return !banded || zones.may_matter(p, li);
                                                      }),
                                 cp, looked_at, ctx);
  if (!figures) return figures.error();
  r.collisions = figures->collisions;
  if (figures->collisions > 0)
    for (const Vec3& p : figures->points)
      if (!violation(p, "an extrusion would hit earlier layers")) return false;
  return true;
}

}  // namespace nonplanar
