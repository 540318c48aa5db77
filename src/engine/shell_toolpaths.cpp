// Notation as in layers/shell_plan.hpp and layers/shell_region.hpp.
#include "engine/shell_toolpaths.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "core/parallel.hpp"
#include "core/polygon_ops.hpp"
#include "engine/top_direction.hpp"
#include "layers/height_contour.hpp"
#include "nonplanar/deform.hpp"
#include "program/reach_groups.hpp"

namespace nonplanar {
namespace {

// The core: planar layers at the plans' boundaries (one core for every shell), layer k kept
// where z_k <= B + a, i.e. where H >= z_k − a + N·t; where the part stands above a top
// somewhere, cut back only inside that shell's R (R[i] of plans[i]).
Expected<std::vector<SlicedLayer>> core_layers(const TriangleMesh& mesh,
                                               const std::vector<double>& z,
                                               const std::vector<layers::ShellPlan>& plans,
                                               const std::vector<std::vector<ExPolygon>>& R,
                                               const Context& ctx) {
  std::vector<SlicedLayer> spans;
  for (std::size_t k = 1; k < z.size(); ++k) {
    SlicedLayer l;
    l.z_bottom = z[k - 1], l.z_top = z[k];
    l.z_slice = 0.5 * (l.z_bottom + l.z_top);
    spans.push_back(l);
  }
  auto core = slice_mesh_at(mesh, std::move(spans), ctx);
  if (!core) return core.error();
  struct Top {
    double lo, hi;
    layers::ContourIndex index;
  };
  std::vector<Top> tops;
  for (const layers::ShellPlan& plan : plans) {
    const auto [lo_it, hi_it] = std::minmax_element(plan.top.h.begin(), plan.top.h.end());
    tops.push_back({*lo_it, *hi_it, layers::ContourIndex(plan.top)});
  }
  core::parallel_for(std::size_t{0}, core->size(), [&](std::size_t k) {
    SlicedLayer& L = (*core)[k];
    if (L.islands.empty()) return;
    std::vector<ExPolygon> cut;
    for (std::size_t i = 0; i < plans.size(); ++i) {
      const double level = plans[i].core_level(L.z_top);
      if (level <= tops[i].lo) continue;
      // The shell over the part cut away counts as cover for the skins below, so they are as
      // thick (shell included) as top_solid_layers asks, not that plus the shell.
      if (L.covers.empty()) L.covers = L.islands;
      if (plans[i].region.empty()) {  // the one shell, over the whole part
        L.islands = level > tops[i].hi
                        ? std::vector<ExPolygon>{}
                        : clip::intersection_ex(L.islands, tops[i].index.region_at_least(level));
        return;
      }
      const std::vector<ExPolygon> c =
          level > tops[i].hi ? R[i] : clip::diff_ex(R[i], tops[i].index.region_at_least(level));
      cut.insert(cut.end(), c.begin(), c.end());
    }
    if (!cut.empty()) L.islands = clip::diff_ex(L.islands, cut);
  });
  while (!core->empty() && core->back().islands.empty()) core->pop_back();
  return core;
}

// A bead shorter than this (in XY, mm) is a blob between a retraction and its give-back, not a
// line: the shell's pieces cut between the core's layers and the slivers of its region left
// 1015 of them in the bunny's file and 511 in the two reliefs' (a planar print has none).
constexpr double kShortestRun = 0.1;

double xy_length(const ExtrusionPath& p) {
  double l = 0;
  for (std::size_t i = 1; i < p.points.size(); ++i)
    l += (p.points[i] - p.points[i - 1]).head<2>().norm();
  return l;
}

// The pieces of one shell path between the core's layer tops: `slot` of a point is how many
// core layers are printed before it (tops[k] <= its slot level). A segment whose ends fall in
// different slots is cut where the level crosses the top between them (by bisection).
void split_by_slot(const ExtrusionPath& p, const layers::ShellPlan& plan,
                   const std::vector<double>& tops,
                   const std::function<void(int, ExtrusionPath&&)>& emit_any) {
  auto emit = [&](int slot, ExtrusionPath&& piece) {
    if (xy_length(piece) >= kShortestRun) emit_any(slot, std::move(piece));
  };
  auto slot_of = [&](const Vec3& q) {
    const double v = plan.slot_level(q.x(), q.y(), q.z());
    return std::max(1,
                    static_cast<int>(std::upper_bound(tops.begin(), tops.end(), v) - tops.begin()));
  };
  // Segments cut to 0.2 mm first: along a long one U + s need not be monotone, and a point
  // inside it could belong to another slot than both ends.
  ExtrusionPath fine;
  fine.points.assign(1, p.points.front()), fine.height.assign(1, p.height.front());
  for (std::size_t i = 1; i < p.points.size(); ++i) {
    const Vec3 &a = p.points[i - 1], &b = p.points[i];
    const int n = 1 + static_cast<int>((b - a).head<2>().norm() / 0.2);
    for (int k = 1; k <= n; ++k) {
      const double f = static_cast<double>(k) / n;
      fine.points.push_back(a + (b - a) * f);
      fine.height.push_back(p.height[i - 1] + (p.height[i] - p.height[i - 1]) * f);
    }
  }
  ExtrusionPath empty = p;  // the path's role, width and speed, without points
  empty.points.clear(), empty.height.clear();
  ExtrusionPath piece = empty;
  piece.points.assign(1, fine.points.front()), piece.height.assign(1, fine.height.front());
  int slot = slot_of(fine.points.front());
  for (std::size_t i = 1; i < fine.points.size(); ++i) {
    const Vec3 &a = fine.points[i - 1], &b = fine.points[i];
    const double ha = fine.height[i - 1], hb = fine.height[i];
    double start = 0;  // along a → b: where the current piece begins on this segment
    for (int next = slot_of(b), guard = 0; next != slot && guard < 1000; ++guard) {
      // The crossing of the nearest top on the way to `next`, on [start, 1] along a → b. Not
      // the top next to `next`: a point where g steps (a level several slots away) would leave
      // the slots in between in this piece, printed after what should follow it (on the spiky
      // block, a shell point 0.105 mm over a later one 0.45 mm away).
      const bool rising = next > slot;
      const double top = tops[static_cast<std::size_t>(rising ? slot : slot - 1)];
      double lo = start, hi = 1;
      for (int it = 0; it < 30; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Vec3 q = a + (b - a) * mid;
        ((plan.slot_level(q.x(), q.y(), q.z()) >= top) == rising ? hi : lo) = mid;
      }
      const Vec3 q = a + (b - a) * hi;
      const double hq = ha + (hb - ha) * hi;
      piece.points.push_back(q), piece.height.push_back(hq);
      // (Where g steps, the slots in between get no length: nothing to print.)
      if (piece.points.size() > 2 || (piece.points.size() == 2 && hi > start))
        emit(slot, std::move(piece));
      piece = empty;
      piece.points.assign(1, q), piece.height.assign(1, hq);
      start = hi;
      slot = slot_of(q + (b - q) * 1e-6);
      if (slot == next) break;
    }
    piece.points.push_back(b), piece.height.push_back(hb);
  }
  if (piece.points.size() >= 2) emit(slot, std::move(piece));
}

// Where the part stands above the top: each shell point after the core's layers up to its slot
// level, the rest of the core after it (shell_region.hpp). Slot k holds, layer by layer in print
// order, the pieces printed between core layers k − 1 and k (k = K: after the whole core).
// With several shells, each one's pieces in a slot follow the one's before it (their patches
// lie beyond the head's reach of each other's; the gate checks what they print). The pieces of
// a layer in a slot are printed group by group (program::order_reach_groups): a band beside a
// wall is cut into pieces on all sides of the wall, and in the order of the layer's paths they
// sent the nozzle round it between two pieces.
std::vector<LayerToolpaths> interleave(std::vector<LayerToolpaths> core,
                                       const std::vector<double>& tops,
                                       const std::vector<std::vector<LayerToolpaths>>& shells,
                                       const std::vector<layers::ShellPlan>& plans,
                                       const Toolhead& head) {
  const std::size_t K = core.size();
  std::vector<std::vector<LayerToolpaths>> slots = shell_slots(shells, plans, tops);
  // A shell point printed before core layer k lies at most s⁻ (about 0.1 mm) over its top: a
  // core layer under the highest shell point so far travels over it lifted.
  std::vector<LayerToolpaths> out;
  double shell_so_far = -1e300;
  Vec2 at(0, 0);  // where the nozzle is, after the layers so far
  for (std::size_t k = 0; k <= K; ++k) {
    for (LayerToolpaths& part : slots[k]) {
      shell_so_far = std::max(shell_so_far, part.max_z);
      order_piece(part, head, at);
      out.push_back(std::move(part));
    }
    if (k == K) break;
    LayerToolpaths& L = core[k];
    for (auto p = L.paths.rbegin(); p != L.paths.rend(); ++p)
      if (!p->points.empty()) {
        at = p->points.back().head<2>();
        break;
      }
    if (L.z < shell_so_far) L.nonplanar = true, L.max_z = std::max(L.max_z, shell_so_far);
    out.push_back(std::move(L));
  }
  return out;
}

}  // namespace

Expected<std::vector<LayerToolpaths>> shell_curved_layers(const TriangleMesh& mesh,
                                                          const layers::ShellPlan& plan,
                                                          const std::vector<ExPolygon>& R,
                                                          const PrintConfig& print,
                                                          const Context& ctx) {
  const bool partial = !plan.region.empty();
  // The shell: normalised so its layers are the planes ζ = j·t … (j + 1)·t.
  const layers::ShellField field(plan);
  // Where the part stands above the top, H carried over it bends the map hard: to 0.005 mm the
  // ankle base's 1196 faces became 1.8 million in 12 rounds (4.4 s). The slab's contours need
  // no more than a bead's precision; its points are mapped back exactly.
  NormalizeParams np = shell_normalize_params(mesh);
  if (partial) np.tolerance = 0.02, np.max_rounds = 8;
  if (plan.framed)  // R lies inside H's raster
    np.care_min = plan.top.origin,
    np.care_max = plan.top.origin + Vec2(plan.top.nx - 1, plan.top.ny - 1) * plan.top.cell;
  auto normalized = normalize_mesh(mesh, field, np, ctx);
  if (!normalized) return normalized.error();
  // An empty layer first stands for the bed-side neighbour make_toolpaths treats specially
  // (first-layer width and speed, the skirt): the shell is never the first layer printed.
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
  // The top's lines up and down its slopes (top_direction.hpp). Layer i of the cut has its
  // lines at fill_angle + 90°·(i mod 2); the top is i = N.
  if (const auto dir = top_slope_direction(mesh, plan, 2.0, 45.0))
    tp.fill_angle = *dir - 90.0 * (plan.N % 2);
  auto planar = make_toolpaths(*cut, tp, ctx);
  if (!planar) return planar.error();
  planar->erase(planar->begin());
  MapBackParams back;  // the default chords, the printer's head for the top skins' order
  back.passes.head = print.toolhead;
  auto mapped = map_toolpaths_back(*planar, field, back, ctx);
  if (!mapped) return mapped.error();
  std::vector<LayerToolpaths> paths;
  for (std::size_t j = 0; j < mapped->size(); ++j) {
    LayerToolpaths& L = (*mapped)[j];
    L.paths.erase(
        std::remove_if(L.paths.begin(), L.paths.end(),
                       [](const ExtrusionPath& p) { return xy_length(p) < kShortestRun; }),
        L.paths.end());
    if (L.paths.empty()) continue;
    for (ExtrusionPath& p : L.paths)
      for (std::size_t k = 0; k < p.points.size(); ++k)
        p.height[k] = plan.thickness(static_cast<int>(j), p.points[k].x(), p.points[k].y());
    L.z = L.max_z;
    L.height = plan.t;
    paths.push_back(std::move(L));
  }
  return paths;
}

std::vector<std::vector<LayerToolpaths>> shell_slots(
    const std::vector<std::vector<LayerToolpaths>>& shells,
    const std::vector<layers::ShellPlan>& plans, const std::vector<double>& tops) {
  const std::size_t K = tops.size();
  std::vector<std::vector<LayerToolpaths>> slots(K + 1);
  for (std::size_t i = 0; i < shells.size(); ++i)
    for (const LayerToolpaths& L : shells[i]) {
      const layers::ShellPlan& plan = plans[i];
      std::vector<LayerToolpaths*> in(K + 1, nullptr);
      for (const ExtrusionPath& p : L.paths)
        split_by_slot(p, plan, tops, [&](int k, ExtrusionPath&& piece) {
          auto& s = slots[static_cast<std::size_t>(k)];
          if (!in[static_cast<std::size_t>(k)]) {
            LayerToolpaths part;  // L's figures, none of its paths yet
            part.height = L.height, part.nonplanar = L.nonplanar, part.max_slope = L.max_slope;
            part.max_z = -1e300;
            s.push_back(std::move(part));
            in[static_cast<std::size_t>(k)] = &s.back();
          }
          LayerToolpaths& part = *in[static_cast<std::size_t>(k)];
          for (const Vec3& q : piece.points) part.max_z = std::max(part.max_z, q.z());
          part.z = part.max_z;
          part.paths.push_back(std::move(piece));
        });
      // The pointers into `slots` stay valid: each slot gains one part per shell layer, and
      // the next layer's parts are pushed only after this layer is done.
    }
  return slots;
}

void order_piece(LayerToolpaths& part, const Toolhead& head, Vec2& at) {
  std::vector<ExtrusionPath> ordered;
  ordered.reserve(part.paths.size());
  for (std::size_t i : program::order_reach_groups(part.paths, head, at))
    ordered.push_back(std::move(part.paths[i]));
  part.paths = std::move(ordered);
  for (auto p = part.paths.rbegin(); p != part.paths.rend(); ++p)
    if (!p->points.empty()) {
      at = p->points.back().head<2>();
      break;
    }
}

Expected<std::vector<LayerToolpaths>> shell_toolpaths(const TriangleMesh& mesh,
                                                      const std::vector<layers::ShellPlan>& plans,
                                                      const PrintConfig& print, const Context& ctx,
                                                      const CoreStacks& stacks) {
  if (plans.empty()) return Error{Status::internal_error, "shell_toolpaths: no shell"};
  std::vector<std::vector<ExPolygon>> R;
  std::vector<std::vector<LayerToolpaths>> shells;
  // The shells first: their maps may refuse them (shell_normalize_params) before the core.
  for (const layers::ShellPlan& plan : plans) {
    R.push_back(plan.region.empty() ? std::vector<ExPolygon>{}
                                    : layers::region_at_least(plan.region.as_top(), 0));
    auto paths = shell_curved_layers(mesh, plan, R.back(), print, ctx);
    if (!paths) return paths.error();
    shells.push_back(std::move(*paths));
  }
  // With stacks the core is cut from the normalised mesh: outside the stacks' bands its
  // layers are the planar ones, and the cut under the shells lies there.
  // A stack may hold more layers than the planar ones it replaces: the core goes on, h_c at a
  // time, as high as the normalised mesh.
  std::optional<NormalizedMesh> normalized;
  std::vector<double> z = plans.front().core;
  if (stacks.field) {
    auto n = normalize_mesh(mesh, *stacks.field, {}, ctx);
    if (!n) return n.error();
    normalized = std::move(*n);
    const double top = bounding_box(normalized->mesh).max.z();
    const double h_c = z.size() >= 3 ? z[z.size() - 1] - z[z.size() - 2] : 0;
    while (h_c > 0 && z.back() < top - 1e-9) z.push_back(z.back() + h_c);
  }
  auto core = core_layers(normalized ? normalized->mesh : mesh, z, plans, R, ctx);
  if (!core) return core.error();
  normalized.reset();
  ctx.progress("core", 1.0);
  std::vector<LayerToolpaths> core_paths;
  if (!core->empty()) {
    auto paths = make_toolpaths(*core, print.paths, ctx);
    if (!paths) return paths.error();
    core_paths = std::move(*paths);
  }
  if (stacks.field && !core_paths.empty()) {
    auto mapped = map_toolpaths_back(core_paths, *stacks.field, stacks.map_back, ctx);
    if (!mapped) return mapped.error();
    core_paths = std::move(*mapped);
  }
  if (plans.front().region.empty() || core_paths.empty()) {
    std::vector<LayerToolpaths> out = std::move(core_paths);
    for (std::vector<LayerToolpaths>& shell : shells)
      for (LayerToolpaths& L : shell) out.push_back(std::move(L));
    return out;
  }
  std::vector<double> tops;
  for (std::size_t k = 0; k < core_paths.size(); ++k) tops.push_back((*core)[k].z_top);
  return interleave(std::move(core_paths), tops, shells, plans, print.toolhead);
}

}  // namespace nonplanar
