// The pipeline (DESIGN.md §2): every stage is a free function; this only chains them and
// checks the result against DESIGN.md §3 before anyone writes it.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nonplanar/deform.hpp"
#include "nonplanar/pipeline.hpp"

namespace nonplanar {

SliceJob make_job(const PrintConfig& print, double max_angle_deg) {
  SliceJob j;
  j.print = print;
  j.analysis.max_angle_deg = max_angle_deg;
  j.layers.layer_height = print.slice.layer_height;
  j.layers.first_layer_height = print.slice.first_layer_height;
  j.layers.max_angle_deg = max_angle_deg;
  j.layers.min_layer_height = std::min(j.analysis.min_layer_height, print.slice.layer_height);
  j.layers.max_layer_height =
      std::max(1.5 * print.slice.layer_height, std::min(0.75 * print.paths.nozzle_diameter, 0.3));
  j.analysis.min_layer_height = j.layers.min_layer_height;
  return j;
}

Expected<SliceResult> slice_model(const TriangleMesh& mesh, const SliceJob& job,
                                  const Context& ctx) {
  SliceResult r;
  r.header.push_back(std::string("mode: ") + (job.planar_only ? "planar" : "non-planar"));
  const TriangleMesh* to_slice = &mesh;
  TriangleMesh normalized;
  if (!job.planar_only) {
    auto a = analyze(mesh, job.analysis, ctx);
    if (!a) return a.error();
    std::vector<SurfaceFit> fits;
    std::vector<int> ids;
    for (std::size_t i = 0; i < a->patches.size(); ++i) {
      if (!a->patches[i].needs_nonplanar()) continue;
      auto f = fit_patch(mesh, a->patches[i], job.fit, ctx);
      if (!f) return f.error();
      fits.push_back(std::move(*f));
      ids.push_back(static_cast<int>(i));
    }
    auto plan = plan_layers(mesh, *a, fits, ids, job.layers, ctx);
    if (!plan) return plan.error();
    r.plan = std::move(*plan);
    for (const auto& fb : r.plan.fallbacks)
      r.notices.push_back("patch " + std::to_string(fb.patch) + " printed planar: " + fb.reason);
    if (r.plan.stacks.empty()) {
      r.notices.push_back(ids.empty() ? "no surface needs non-planar layers; slicing planar"
                                      : "no patch can be printed non-planar; slicing planar");
    } else {
      auto n = normalize_mesh(mesh, *r.plan.field, {}, ctx);
      if (!n) return n.error();
      normalized = std::move(n->mesh);
      to_slice = &normalized;
      r.nonplanar = true;
      char buf[160];
      for (const LayerStack& st : r.plan.stacks) {
        std::snprintf(buf, sizeof buf, "patch %d: %d curved layers from z = %.2f mm", st.patch,
                      st.layers, st.c);
        r.header.push_back(buf);
      }
    }
  }
  auto sliced = slice_mesh(*to_slice, job.print.slice, ctx);
  if (!sliced) return sliced.error();
  auto paths = make_toolpaths(*sliced, job.print.paths, ctx);
  if (!paths) return paths.error();
  if (!r.nonplanar) {
    r.layers = std::move(*paths);
  } else {
    auto mapped = map_toolpaths_back(*paths, *r.plan.field, {}, ctx);
    if (!mapped) return mapped.error();
    r.layers = std::move(*mapped);
  }

  // Safety (DESIGN.md §3): thickness and slope from the paths themselves, collisions with
  // earlier layers from the independent check. Any violation is a bug: refuse.
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
          if (p.height[k] < L.min_layer_height - 1e-3 || p.height[k] > L.max_layer_height + 1e-3) {
            char buf[200];
            std::snprintf(buf, sizeof buf,
                          "safety check: layer %zu is %.3f mm thick at (%.2f, %.2f, %.2f), outside "
                          "[%.2f, %.2f]",
                          li + 1, p.height[k], p.points[k].x(), p.points[k].y(), p.points[k].z(),
                          L.min_layer_height, L.max_layer_height);
            return Error{Status::internal_error, buf};
          }
        }
        if (k == 0) continue;
        const double dxy = (p.points[k] - p.points[k - 1]).head<2>().norm();
        const double dz = std::abs(p.points[k].z() - p.points[k - 1].z());
        if (dxy > 0.05) r.steepest_deg = std::max(r.steepest_deg, std::atan2(dz, dxy) * 180 / M_PI);
        if (dxy > 0.05 && dz > tan_max * dxy) {
          char buf[200];
          std::snprintf(
              buf, sizeof buf, "safety check: extrusion at (%.2f, %.2f, %.2f) is %.1f deg steep",
              p.points[k].x(), p.points[k].y(), p.points[k].z(), std::atan2(dz, dxy) * 180 / M_PI);
          return Error{Status::internal_error, buf};
        }
      }
    }
  if (r.thickness_min > r.thickness_max) r.thickness_min = r.thickness_max = 0;
  CheckParams cp;
  cp.max_angle_deg = L.max_angle_deg;
  cp.layer_height = L.layer_height;
  cp.nozzle_tip_radius = L.nozzle_tip_radius;
  cp.nozzle_angle_deg = L.nozzle_angle_deg;
  cp.block_radius = L.block_radius;
  cp.block_clearance = L.block_clearance;
  cp.filament_diameter = job.print.gcode.filament_diameter;
  auto figures = check_print(moves_from_toolpaths(r.layers, job.print.gcode), nullptr, cp, ctx);
  if (!figures) return figures.error();
  r.collisions = figures->collisions;
  if (figures->collisions > 0) {
    char buf[200];
    const Vec3& c = figures->first_collision;
    std::snprintf(
        buf, sizeof buf,
        "safety check: %zu extrusion points would hit earlier layers, first at (%.2f, %.2f, %.2f)",
        figures->collisions, c.x(), c.y(), c.z());
    return Error{Status::internal_error, buf};
  }
  return r;
}

}  // namespace nonplanar
