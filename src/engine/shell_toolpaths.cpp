#include "engine/shell_toolpaths.hpp"
#include "core/parallel.hpp"

#include <algorithm>

#include "core/polygon_ops.hpp"
#include "layers/height_contour.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {

Expected<std::vector<LayerToolpaths>> shell_toolpaths(const TriangleMesh& mesh,
                                                      const layers::ShellPlan& plan,
                                                      const PrintConfig& print,
                                                      const Context& ctx) {
  // The core: planar layers at the plan's boundaries, layer k kept where z_k <= B + a, i.e.
  // where H >= z_k − a + N·t.
  std::vector<SlicedLayer> spans;
  for (std::size_t k = 1; k < plan.core.size(); ++k) {
    SlicedLayer l;
    l.z_bottom = plan.core[k - 1], l.z_top = plan.core[k];
    l.z_slice = 0.5 * (l.z_bottom + l.z_top);
    spans.push_back(l);
  }
  auto core = slice_mesh_at(mesh, std::move(spans), ctx);
  if (!core) return core.error();
  const auto [lo_it, hi_it] = std::minmax_element(plan.top.h.begin(), plan.top.h.end());
  const double h_lo = *lo_it, h_hi = *hi_it;
  const layers::ContourIndex index(plan.top);
  // Where the part stands above the top somewhere, the shell prints in R only: the core is cut
  // back only there, and a layer above insert_z is split into its part in R (printed before
  // the shell) and the rest (after it), as separate islands.
  const bool partial = !plan.region.empty();
  const std::vector<ExPolygon> R =
      partial ? layers::region_at_least(plan.region, 0) : std::vector<ExPolygon>{};
  core::parallel_for(std::size_t{0}, core->size(), [&](std::size_t k) {
    SlicedLayer& L = (*core)[k];
    const double level = plan.core_level(L.z_top);
    const bool split = partial && L.z_top > plan.insert_z + 1e-9;
    if ((level <= h_lo && !split) || L.islands.empty()) return;
    // The shell over the part cut away counts as cover for the skins below, so they are as
    // thick (shell included) as top_solid_layers asks, not that plus the shell.
    L.covers = L.islands;
    if (!partial) {
      L.islands = level > h_hi ? std::vector<ExPolygon>{}
                               : clip::intersection_ex(L.islands, index.region_at_least(level));
      return;
    }
    const std::vector<ExPolygon> cut = level <= h_lo ? std::vector<ExPolygon>{}
                                       : level > h_hi
                                           ? R
                                           : clip::diff_ex(R, index.region_at_least(level));
    std::vector<ExPolygon> kept = cut.empty() ? L.islands : clip::diff_ex(L.islands, cut);
    if (split) {
      std::vector<ExPolygon> in = clip::intersection_ex(kept, R), out = clip::diff_ex(kept, R);
      kept = std::move(in);
      kept.insert(kept.end(), out.begin(), out.end());
    }
    L.islands = std::move(kept);
  });
  while (!core->empty() && core->back().islands.empty()) core->pop_back();
  ctx.progress("core", 1.0);
  std::vector<LayerToolpaths> out, after;
  if (!core->empty()) {
    auto paths = make_toolpaths(*core, print.paths, ctx);
    if (!paths) return paths.error();
    for (std::size_t k = 0; k < paths->size(); ++k) {
      LayerToolpaths& L = (*paths)[k];
      if (!partial || (*core)[k].z_top <= plan.insert_z + 1e-9) {
        out.push_back(std::move(L));
        continue;
      }
      LayerToolpaths in = L, rest = L;
      in.paths.clear(), rest.paths.clear();
      for (ExtrusionPath& p : L.paths) {
        std::size_t inside = 0;
        for (const Vec3& q : p.points) inside += plan.in_region(q.x(), q.y());
        (2 * inside >= p.points.size() ? in : rest).paths.push_back(std::move(p));
      }
      if (!in.paths.empty()) out.push_back(std::move(in));
      if (!rest.paths.empty()) after.push_back(std::move(rest));
    }
  }

  // The shell: normalised so its layers are the planes ζ = j·t … (j + 1)·t. An empty layer
  // first stands for the bed-side neighbour make_toolpaths treats specially (first-layer
  // width and speed, the skirt): the shell is never the first layer printed.
  const layers::ShellField field(plan);
  auto normalized = normalize_mesh(mesh, field, {}, ctx);
  if (!normalized) return normalized.error();
  std::vector<SlicedLayer> shell(static_cast<std::size_t>(plan.N) + 1);
  for (int j = -1; j < plan.N; ++j) {
    SlicedLayer& l = shell[static_cast<std::size_t>(j + 1)];
    l.z_bottom = j * plan.t, l.z_top = (j + 1) * plan.t;
    l.z_slice = (j + 0.5) * plan.t;
  }
  auto cut = slice_mesh_at(normalized->mesh, std::move(shell), ctx);
  if (!cut) return cut.error();
  (*cut)[0].islands.clear();
  if (partial)  // outside R the part stands above H: the core prints it
    for (SlicedLayer& l : *cut) l.islands = clip::intersection_ex(l.islands, R);
  ToolpathParams tp = print.paths;
  tp.skirts = 0;
  auto planar = make_toolpaths(*cut, tp, ctx);
  if (!planar) return planar.error();
  planar->erase(planar->begin());
  auto mapped = map_toolpaths_back(*planar, field, {}, ctx);
  if (!mapped) return mapped.error();
  double shell_top = 0;
  for (std::size_t j = 0; j < mapped->size(); ++j) {
    LayerToolpaths& L = (*mapped)[j];
    if (L.paths.empty()) continue;
    for (ExtrusionPath& p : L.paths)
      for (std::size_t k = 0; k < p.points.size(); ++k)
        p.height[k] = plan.thickness(static_cast<int>(j), p.points[k].x(), p.points[k].y());
    L.z = L.max_z;
    L.height = plan.t;
    shell_top = std::max(shell_top, L.max_z);
    out.push_back(std::move(L));
  }
  // The core outside R above insert_z, after the shell. Its layers below the shell's top travel
  // over it lifted, as over a curved layer.
  for (LayerToolpaths& L : after) {
    if (L.z < shell_top) L.nonplanar = true, L.max_z = std::max(L.max_z, shell_top);
    out.push_back(std::move(L));
  }
  return out;
}

}  // namespace nonplanar
