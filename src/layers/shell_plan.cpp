// Notation as in shell_plan.hpp.
#include "layers/shell_plan.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/column_caster.hpp"
#include "core/parallel.hpp"

namespace nonplanar::layers {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMargin = 0.01;  ///< m: the stairs' thickness stays this far inside the limits
/// A face whose normal points down by less than this (|n_z| = sin of the wall's lean from the
/// vertical: 45°) is a wall each layer prints over the one below, as planar slicing does: the
/// downhill side of a tilted bore under a tilted ring, not an overhang the shell would rest on.
constexpr double kSelfSupporting = 0.7071;

// z_1 … up to `end`: steps of at most h_c, landing on each target that can be reached in
// steps no thinner than h_min.
std::vector<double> core_boundaries(double h1, double h_c, double h_min, double end,
                                    std::vector<double> targets) {
  std::vector<double> z{0.0, h1};
  std::sort(targets.begin(), targets.end());
  double cur = h1;
  for (double target : targets) {
    if (target > end) break;
    const double gap = target - cur;
    if (gap < h_min - 1e-9) continue;
    const int n = static_cast<int>(std::ceil(gap / h_c - 1e-9));
    if (gap / n < h_min - 1e-9) continue;
    for (int k = 1; k <= n; ++k) z.push_back(cur + gap * k / n);
    z.back() = cur = target;
  }
  while (cur < end - 1e-9) z.push_back(cur += h_c);
  return z;
}

// The core's layer height: the shell's lowest layer fills a stair of up to h_c over t − a and
// stays within the layer limits (kMargin inside them).
double core_layer_height(const LayerParams& p) {
  return std::min(p.layer_height, p.max_layer_height - p.min_layer_height - 2 * kMargin);
}

// The shell's t, N and reach over `patches`.
void set_layers(ShellPlan& s, const Analysis& a, const std::vector<int>& patches,
                const LayerParams& p) {
  // As thick as the nozzle tip's flat needs on the steepest facet (stack_builder's rule: a
  // layer thinner than (r + 0.1)·tan θ − h/2 fires the collision test uphill), else the
  // profile's layer height: at 0.15 mm and 30° the shell's layers must be 0.22 mm.
  double steepest = 0;
  for (int i : patches)
    steepest = std::max(steepest, a.patches[static_cast<std::size_t>(i)].max_slope_deg);
  const double tip =
      (p.toolhead.tip_radius + 0.1) * std::tan(steepest * kDeg) - 0.5 * p.layer_height;
  s.t = std::max(p.layer_height, std::ceil(tip * 100 - 1e-9) / 100);
  s.reach = s.t - p.min_layer_height - kMargin;
  // A shell of about two layers: the core prints its own top solid layers under it, so the
  // shell only has to fill the stairs and lay the top; each layer more costs print time and
  // gains nothing measurable (four against two on ten real parts: the share within 0.03 mm
  // moved by at most 0.009, the prints took 2-22 % longer). Features below keep planar layers.
  s.N = p.shell_layers > 0 ? p.shell_layers
                           : std::max(2, static_cast<int>(std::ceil(0.4 / s.t - 1e-9)));
}

// The core's first layer: the profile's where no stair of the shell's lowest layer comes down
// to it (B + a >= z_1 wherever H is, `lowest` the least of H − N·t + a): a slicer that slices
// the core in the same run as the shell (prepare) prints its own first layer height. Else at
// most h_c, as every stair.
double core_first_layer(double lowest, const LayerParams& p) {
  return lowest >= p.first_layer_height + 1e-6
             ? p.first_layer_height
             : std::min(p.first_layer_height, core_layer_height(p));
}

// The heights the core's boundaries land on: the flat patches' (none on an even core).
std::vector<double> core_targets(const Analysis& a, bool even_core) {
  std::vector<double> targets;
  for (const Patch& q : a.patches)
    if (!even_core && q.verdict == PatchVerdict::flat && q.z_max - q.z_min < 0.05)
      targets.push_back(0.5 * (q.z_min + q.z_max));  // the wing's tilted floor: 3.55–3.58 mm
  return targets;
}

// Overhangs (leaning over 45°) and other printable up-facing surfaces (not of the patches) within
// `overhang` (overhangs) or half a millimetre (tops) under the shell's bottom, inside R: why the
// shell cannot rest on the core there, naming the first place (empty when none), and every such
// face.
struct Under {
  std::string why;
  std::vector<char> faces;
};
Under under_shell(const TriangleMesh& mesh, const std::vector<char>& in_patch, const ShellPlan& s,
                  double max_angle_deg, double overhang) {
  Under u;
  u.faces.assign(mesh.faces.size(), 0);
  const double cos_max = std::cos(max_angle_deg * kDeg);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (in_patch[f]) continue;
    const auto& F = mesh.faces[f];
    const Vec3 v[3] = {mesh.vertices[F[0]], mesh.vertices[F[1]], mesh.vertices[F[2]]};
    const Vec3 nrm = (v[1] - v[0]).cross(v[2] - v[0]);
    const double len = nrm.norm();
    if (!(len > 0)) continue;
    const double nz = nrm.z() / len;
    const bool on_bed = std::max({v[0].z(), v[1].z(), v[2].z()}) < 1e-6;
    const bool is_overhang = nz < -kSelfSupporting && !on_bed;
    const bool printable_top = nz > cos_max;
    if (!is_overhang && !printable_top) continue;
    const double margin = is_overhang ? overhang : 0.5;
    const Vec3 c = (v[0] + v[1] + v[2]) / 3.0;
    for (const Vec3& q : {v[0], v[1], v[2], c})
      if (s.in_region(q.x(), q.y()) && q.z() > s.bottom(q.x(), q.y()) - margin) {
        if (u.why.empty())
          u.why = notice_at(is_overhang ? "an overhang lies under the shell"
                                        : "another printable surface lies under the shell",
                            q);
        u.faces[f] = 1;
        break;
      }
  }
  return u;
}

// The shell's top: the patches' facets, and the printable facets joined to them (through
// shared vertices, one after another) that no stack could take: those touching a curvature
// jump (in no patch: a NURBS fit cannot follow them) and those of patches too small to fit. A
// shell follows the facets themselves (H), so neither reason keeps them out of it: Benchy's
// hull and deck, where 13 956 of its 22 254 printable facets touch a curvature jump, went from
// 50 % of the curved top within 0.03 mm to 82 %. Flat patches stay out (the core lands on
// them), and so do facets apart from the patches (the Voron ornament's, round its cap).
Patch shell_top(const TriangleMesh& mesh, const Analysis& a, const std::vector<int>& patches) {
  Patch P;
  P.xy_min = Vec2::Constant(1e300), P.xy_max = Vec2::Constant(-1e300);
  P.z_min = 1e300, P.z_max = -1e300;
  for (int i : patches) {
    const Patch& q = a.patches[static_cast<std::size_t>(i)];
    P.faces.insert(P.faces.end(), q.faces.begin(), q.faces.end());
    P.xy_min = P.xy_min.cwiseMin(q.xy_min), P.xy_max = P.xy_max.cwiseMax(q.xy_max);
    P.z_min = std::min(P.z_min, q.z_min), P.z_max = std::max(P.z_max, q.z_max);
  }
  const std::size_t F = mesh.faces.size();
  if (P.faces.empty() || a.painted.size() != F || a.face_patch.size() != F ||
      a.discontinuous.size() != F)
    return P;
  // The candidates by vertex; a vertex of the top takes in every candidate round it.
  std::vector<std::vector<int>> at(mesh.vertices.size());
  for (std::size_t f = 0; f < F; ++f) {
    if (!a.painted[f]) continue;
    const int q = a.face_patch[f];
    if (q < 0 ? a.discontinuous[f] != 0
              : a.patches[static_cast<std::size_t>(q)].verdict == PatchVerdict::too_small)
      for (int v : mesh.faces[f]) at[static_cast<std::size_t>(v)].push_back(static_cast<int>(f));
  }
  std::vector<char> in(F, 0), reached(mesh.vertices.size(), 0);
  std::vector<int> todo;
  auto reach = [&](int f) {
    for (int v : mesh.faces[static_cast<std::size_t>(f)])
      if (!reached[static_cast<std::size_t>(v)])
        reached[static_cast<std::size_t>(v)] = 1, todo.push_back(v);
  };
  for (int f : P.faces) in[static_cast<std::size_t>(f)] = 1, reach(f);
  while (!todo.empty()) {
    const int v = todo.back();
    todo.pop_back();
    for (int f : at[static_cast<std::size_t>(v)]) {
      if (in[static_cast<std::size_t>(f)]) continue;
      in[static_cast<std::size_t>(f)] = 1, reach(f);
      P.faces.push_back(f);
      for (int w : mesh.faces[static_cast<std::size_t>(f)]) {
        const Vec3& p = mesh.vertices[static_cast<std::size_t>(w)];
        P.xy_min = P.xy_min.cwiseMin(p.head<2>()), P.xy_max = P.xy_max.cwiseMax(p.head<2>());
        P.z_min = std::min(P.z_min, p.z()), P.z_max = std::max(P.z_max, p.z());
      }
    }
  }
  return P;
}

// R, the slack and g into the plan, and the notice of what the core prints of the patches.
void take_region(ShellPlan& s, ShellRegion&& r) {
  s.left_out.clear();
  if (r.left_out >= 0.5 && !r.why_out.empty()) {
    char buf[60];
    std::snprintf(buf, sizeof buf, "%.0f mm² of it printed planar: ", r.left_out);
    s.left_out = buf;
    for (std::size_t k = 0; k < r.why_out.size(); ++k) s.left_out += (k ? "; " : "") + r.why_out[k];
  }
  s.banded = r.banded, s.stands_at = r.stands_at;
  s.region = std::move(r.mask);
  s.slack = std::move(r.slack);
  s.levels = std::move(r.levels);
}

// The shell on the core: with s.N layers if nothing lies within half a millimetre under it;
// else with fewer, down to one, where overhangs keep `thin` under its bottom (a core layer fits
// between a thin wall's ceiling and the stairs); else with s.N layers again, the footprints of
// what lies under it left to the planar core. Sets s.N (and R, s.left_out); returns why none of
// these works (empty: one does).
std::string rest_on_core(const TriangleMesh& mesh, const std::vector<char>& in_patch,
                         const LayerParams& p, double thin, ShellPlan& s) {
  const int N0 = s.N;
  Under first = under_shell(mesh, in_patch, s, p.max_angle_deg, 0.5);
  if (first.why.empty()) return {};
  for (s.N = N0 - 1; s.N >= 1; --s.N)
    if (under_shell(mesh, in_patch, s, p.max_angle_deg, thin).why.empty()) return {};
  s.N = N0;
  ShellRegion region =
      shell_region(mesh, in_patch, first.faces, s.N * s.t + 0.5, s.top, s.below, p, s.framed);
  // Both reasons: the ornament's logo plate lies under its shell, and left to the core it
  // stands above the dome round 61 % of it (the second is what a user would change).
  if (!region.refused.empty()) return first.why + "; left to the core, " + region.refused;
  region.why_out.push_back(first.why);
  take_region(s, std::move(region));
  if (!under_shell(mesh, in_patch, s, p.max_angle_deg, 0.5).why.empty()) return first.why;
  return {};
}

// The patches reached from the first (the largest) through neighbours: boxes within kNear of
// each other across and in height. Patches far off (the ornament's hanging loop, 35 mm under
// its cap) make one top over the whole part that the part stands above nearly everywhere.
std::vector<int> neighbourhood(const Analysis& a, const std::vector<int>& candidates) {
  constexpr double kNear = 2.0;  // mm
  auto close = [&](int i, int j) {
    const Patch &P = a.patches[static_cast<std::size_t>(i)],
                &Q = a.patches[static_cast<std::size_t>(j)];
    return P.xy_min.x() - kNear <= Q.xy_max.x() && Q.xy_min.x() - kNear <= P.xy_max.x() &&
           P.xy_min.y() - kNear <= Q.xy_max.y() && Q.xy_min.y() - kNear <= P.xy_max.y() &&
           P.z_min - kNear <= Q.z_max && Q.z_min - kNear <= P.z_max;
  };
  std::vector<char> in(candidates.size(), 0);
  in[0] = 1;
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t i = 0; i < candidates.size(); ++i)
      for (std::size_t j = 0; j < candidates.size() && !in[i]; ++j)
        if (in[j] && close(candidates[i], candidates[j])) in[i] = 1, grew = true;
  }
  std::vector<int> out;
  for (std::size_t i = 0; i < candidates.size(); ++i)
    if (in[i]) out.push_back(candidates[i]);
  return out;
}

// The patches' XY box, mm.
std::pair<Vec2, Vec2> patch_box(const Analysis& a, const std::vector<int>& patches) {
  Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
  for (int i : patches) {
    const Patch& P = a.patches[static_cast<std::size_t>(i)];
    lo = lo.cwiseMin(P.xy_min), hi = hi.cwiseMax(P.xy_max);
  }
  return {lo, hi};
}

// Are two boxes farther apart than `gap` (mm) along x or y?
bool apart(const std::pair<Vec2, Vec2>& A, const std::pair<Vec2, Vec2>& B, double gap) {
  const Vec2 d = (B.first - A.second).cwiseMax(A.first - B.second);
  return d.x() > gap || d.y() > gap;
}

}  // namespace

double ShellPlan::core_top(double x, double y) const {
  const double level = bottom(x, y) + reach;
  const auto it = std::upper_bound(core.begin(), core.end(), level);
  return it == core.begin() ? 0.0 : *(it - 1);
}

double ShellPlan::thickness(int j, double x, double y) const {
  const double u = layer_top(j, x, y);
  const double under = j == 0 ? core_top(x, y) : u - t;
  return u - std::max(under, 0.0);
}

ShellPlan plan_shell(const TriangleMesh& mesh, const Analysis& a, const std::vector<int>& patches,
                     const LayerParams& p, double frame, bool even_core, const Context* cancel,
                     std::string_view whole_only) {
  ShellPlan s;
  auto cancelled = [&] {
    if (!cancel || !cancel->cancelled()) return false;
    s.refused = "cancelled";
    return true;
  };
  s.patches = patches;
  // The patches as one, with the printable facets beside them (shell_top): their facets, box
  // and height range (what faceted_top reads).
  const Patch P = shell_top(mesh, a, patches);
  if (P.faces.empty()) {
    s.refused = "no patch to follow";
    return s;
  }
  const BoundingBox box = bounding_box(mesh);
  const double h_c = core_layer_height(p);
  set_layers(s, a, patches, p);
  if (h_c < p.min_layer_height || s.t < p.min_layer_height || s.t > p.max_layer_height) {
    s.refused = "the layer limits leave no room for the core's stairs under a shell";
    return s;
  }
  // H over the part's footprint (a pad as wide on every side as the patches' farthest side
  // needs); with a frame, over the patches' surroundings only (a further shell: the bunny's
  // tail took a raster twice the bunny's size, 0.5 s a plan).
  const Vec2 lo = box.min.head<2>(), hi = box.max.head<2>();
  double pad = std::max({P.xy_min.x() - lo.x(), P.xy_min.y() - lo.y(), hi.x() - P.xy_max.x(),
                         hi.y() - P.xy_max.y(), 0.0}) +
               1.0;
  Patch framed = P;
  if (frame > 0) {
    framed.xy_min = (lo - Vec2(1, 1)).cwiseMax(P.xy_min - Vec2(frame, frame));
    framed.xy_max = (hi + Vec2(1, 1)).cwiseMin(P.xy_max + Vec2(frame, frame));
    pad = 0, s.framed = true;
  }
  s.top = faceted_top(mesh, framed, 0.1, pad, std::tan(0.8 * p.max_angle_deg * kDeg) / M_SQRT2);
  if (cancelled()) return s;

  // Where the part stands above H, the shell prints only in R (shell_region.hpp); inside R it
  // must rest on the core (rest_on_core: fewer layers over a thin wall, or what lies under it
  // left to the planar core).
  std::vector<char> in_patch(mesh.faces.size(), 0);
  for (int f : P.faces) in_patch[static_cast<std::size_t>(f)] = 1;
  // s⁻ also bounds how far a shell point printed before a core layer rises over it: under the
  // check's h/2 with room for the file's rounding (at the defaults t − a − 0.01 was h/2 itself,
  // and the rib over a void left a shell point 0.100 mm over a later core layer 0.28 mm away).
  s.below = std::min(s.t - s.reach - 0.01, 0.5 * p.layer_height - 0.01);
  ShellRegion region = shell_region(mesh, in_patch, {}, 0, s.top, s.below, p, s.framed);
  if (cancelled()) return s;
  if (!region.refused.empty()) {
    s.refused = region.refused;
    return s;
  }
  take_region(s, std::move(region));
  if (!whole_only.empty() && !s.region.empty()) {
    s.refused = whole_only;
    return s;
  }
  if (const std::string why = rest_on_core(mesh, in_patch, p, 1.5 * h_c - s.reach + 0.05, s);
      !why.empty()) {
    s.refused = why;
    return s;
  }

  // The core: up to the highest B + a, landing on the flat patches' heights.
  double end = 0;
  for (double h : s.top.h) end = std::max(end, h - s.N * s.t + s.reach);
  end = std::min(end, box.max.z());
  if (!s.region.empty()) end = box.max.z();  // the part outside R goes on above the shell
  // (The layer over a stair is z_{k+1} − z_k thick, and the first layer is never that one.)
  double lowest = 1e300;
  for (double h : s.top.h) lowest = std::min(lowest, h - s.N * s.t + s.reach);
  s.core = core_boundaries(core_first_layer(lowest, p), h_c, p.min_layer_height, end,
                           core_targets(a, even_core));
  return s;
}

std::optional<std::vector<double>> region_shells_core(const TriangleMesh& mesh, const Analysis& a,
                                                      const LayerParams& p) {
  // How far over H another facet must be to count (mm): shell_region's R leaves out what
  // stands 0.02 mm above H; this test only has to foresee whether R will be all of H.
  constexpr double kAbove = 0.1;
  const ColumnCaster columns(mesh);
  std::vector<char> curved(mesh.faces.size(), 0);
  for (const Patch& q : a.patches)
    if (q.needs_nonplanar())
      for (int f : q.faces) curved[static_cast<std::size_t>(f)] = 1;
  // Over each curved facet's centre: H is about the highest curved facet there, and the part
  // stands above it where another facet is higher still; and under each other facet's corners
  // (a wall rising from a curved floor's edge). Blocks of facets side by side, each stopping
  // once any has found the part above (a yes or no: the same whatever the threads).
  std::atomic<bool> above{false};
  const auto over_curved = [&](std::size_t f) {
    const auto& F = mesh.faces[f];
    const Vec3 c = (mesh.vertices[F[0]] + mesh.vertices[F[1]] + mesh.vertices[F[2]]) / 3.0;
    double top = c.z(), other = -std::numeric_limits<double>::infinity();
    for (const auto& [z, g] : columns.face_hits(c.x(), c.y())) {
      double& highest = curved[static_cast<std::size_t>(g)] ? top : other;
      highest = std::max(highest, z);
    }
    return other > top + kAbove;
  };
  const auto above_curved = [&](std::size_t f) {
    for (int v : mesh.faces[f]) {
      const Vec3& c = mesh.vertices[static_cast<std::size_t>(v)];
      double top = -std::numeric_limits<double>::infinity();
      for (const auto& [z, g] : columns.face_hits(c.x(), c.y()))
        if (curved[static_cast<std::size_t>(g)]) top = std::max(top, z);
      if (std::isfinite(top) && c.z() > top + kAbove) return true;
    }
    return false;
  };
  core::parallel_blocks(std::size_t{0}, mesh.faces.size(), std::size_t{2048},
                        [&](std::size_t lo, std::size_t hi) {
                          for (std::size_t f = lo; f < hi && !above.load(); ++f)
                            if (curved[f] ? over_curved(f) : above_curved(f)) above = true;
                        });
  if (!above) return std::nullopt;
  // The shell over all the curved patches, H as low as their lowest point (plan_shell's H may
  // be lower beside them: the plan then has another first layer, and says so).
  ShellPlan s;
  std::vector<int> all;
  double lowest = 1e300;
  for (std::size_t i = 0; i < a.patches.size(); ++i)
    if (a.patches[i].needs_nonplanar())
      all.push_back(static_cast<int>(i)), lowest = std::min(lowest, a.patches[i].z_min);
  set_layers(s, a, all, p);
  return core_boundaries(core_first_layer(lowest - s.N * s.t + s.reach, p), core_layer_height(p),
                         p.min_layer_height, bounding_box(mesh).max.z(), core_targets(a, false));
}

namespace {

// The curved patches among `among` (empty: all of them).
std::vector<int> curved_among(const Analysis& a, const std::vector<int>& among) {
  std::vector<int> out;
  for (std::size_t i = 0; i < a.patches.size(); ++i)
    if (a.patches[i].needs_nonplanar() &&
        (among.empty() ||
         std::find(among.begin(), among.end(), static_cast<int>(i)) != among.end()))
      out.push_back(static_cast<int>(i));
  return out;
}

// The shell over fewer patches than `wider`, saying why the wider one is refused (the ankle
// base's rim prints as a shell, its ledge planar: say why not both).
ShellPlan narrowed(ShellPlan s, const std::vector<int>& wider, const std::string& why) {
  std::string names = wider.size() > 1 ? "a shell over patches" : "a shell over patch";
  for (std::size_t k = 0; k < std::min<std::size_t>(wider.size(), 5); ++k)
    names += (k ? ", " : " ") + std::to_string(wider[k]);
  if (wider.size() > 5) names += " and " + std::to_string(wider.size() - 5) + " more";
  s.narrowed = names + ": " + why;
  return s;
}

// The first shell: over all the curved patches among c.among, or else the group near the
// largest, or else the largest alone. `near_plan` (if given) gets the group's plan when all the
// patches' is chosen beside it (choose_shells weighs it when that one is banded).
ShellPlan choose_first(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                       const ShellChoice& c, ShellPlan* near_plan = nullptr) {
  const std::vector<int> all = curved_among(a, c.among);
  if (all.empty()) {
    ShellPlan none;
    none.refused = "no patch needs curved layers";
    return none;
  }
  // All the patches, and (should that be refused) the group near the largest: planned side
  // by side, as each takes a raster of the part's whole top (0.76 and 0.67 s on the bunny,
  // where the first is refused), and plan_shell runs on one core.
  const std::vector<int> near = all.size() > 2 ? neighbourhood(a, all) : std::vector<int>{};
  const bool group = near.size() > 1 && near.size() < all.size();
  ShellPlan plan, some;
  core::parallel_for(0, group ? 2 : 1, [&](int k) {
    if (k == 0) plan = plan_shell(mesh, a, all, p, 0, c.even_core, c.cancel, c.whole_only);
    if (k == 1) some = plan_shell(mesh, a, near, p, 0, c.even_core, c.cancel, c.whole_only);
  });
  if (!plan.refused.empty() && group && some.refused.empty())
    return narrowed(std::move(some), all, plan.refused);
  if (!plan.refused.empty() && all.size() > 1) {
    // The refused plans' rasters go before the next is made: the bunny's two (refused as one
    // slicer run's) held beside the largest patch's plan peaked at 182-185 MB through
    // PrusaSlicer, where the two planned in full had peaked at 143.
    for (ShellPlan* r : {&plan, &some}) r->top = {}, r->region = {}, r->slack = {}, r->levels = {};
    ShellPlan one = plan_shell(mesh, a, {all.front()}, p, 0, c.even_core, c.cancel, c.whole_only);
    if (one.refused.empty())
      return narrowed(std::move(one), group ? near : all, group ? some.refused : plan.refused);
  }
  if (near_plan && group && plan.refused.empty()) *near_plan = std::move(some);
  return plan;
}

}  // namespace

ShellPlan choose_shell(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                       std::string_view whole_only) {
  ShellChoice c;
  c.whole_only = whole_only;
  return choose_first(mesh, a, p, c);
}

std::vector<ShellPlan> choose_shells(const TriangleMesh& mesh, const Analysis& a,
                                     const LayerParams& p, int most) {
  ShellChoice c;
  c.most = most;
  return choose_shells(mesh, a, p, c);
}

namespace {

// After the first of `shells`, the further ones, as choose_shells says.
void add_further(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                 const ShellChoice& c, std::vector<ShellPlan>& shells) {
  const int most = c.most;
  const ShellPlan& first = shells.front();
  if (!first.refused.empty() || first.region.empty()) return;
  std::vector<int> rest;
  for (int i : curved_among(a, c.among))
    if (std::find(first.patches.begin(), first.patches.end(), i) == first.patches.end())
      rest.push_back(i);
  // Each plan costs a raster and its distance maps (0.1–0.3 s on the bunny): twice as many
  // tries as shells wanted, the largest groups first, none under 1 % of the curved area.
  double curved = 0;
  for (const Patch& q : a.patches) curved += q.needs_nonplanar() ? q.area : 0;
  std::vector<std::vector<int>> groups;
  while (!rest.empty() && static_cast<int>(groups.size()) < 2 * (most - 1)) {
    std::vector<int> group = neighbourhood(a, rest);
    std::vector<int> left;
    for (int i : rest)
      if (std::find(group.begin(), group.end(), i) == group.end()) left.push_back(i);
    rest = std::move(left);
    double area = 0;
    for (int i : group) area += a.patches[static_cast<std::size_t>(i)].area;
    if (area >= 0.01 * curved) groups.push_back(std::move(group));
  }
  // Within the head's reach of a shell's patches: its points could print in any order
  // beside that shell's (the gate checks what they print; this keeps it from refusing).
  auto near_a_shell = [&](const std::vector<int>& group) {
    const auto box = patch_box(a, group);
    return std::any_of(shells.begin(), shells.end(), [&](const ShellPlan& s) {
      return !apart(box, patch_box(a, s.patches), p.toolhead.reach());
    });
  };
  // Planned side by side, those apart from the first shell (a few may go unused: near a shell
  // kept meanwhile, or past `most`); H over each group's surroundings only, as far as the head
  // reaches and a little more.
  std::vector<ShellPlan> tried(groups.size());
  const double frame = p.toolhead.reach() + 4;
  core::parallel_for(std::size_t(0), groups.size(), [&](std::size_t k) {
    const std::vector<int>& group = groups[k];
    if (!apart(patch_box(a, group), patch_box(a, first.patches), p.toolhead.reach())) return;
    tried[k] = plan_shell(mesh, a, group, p, frame, c.even_core, c.cancel);
    if (!tried[k].refused.empty() && group.size() > 1)
      tried[k] = plan_shell(mesh, a, {group.front()}, p, frame, c.even_core, c.cancel);
  });
  for (std::size_t k = 0; k < groups.size() && static_cast<int>(shells.size()) < most; ++k) {
    if (near_a_shell(groups[k])) continue;
    ShellPlan& s = tried[k];
    // Every one partial (the core goes on above each), on one core.
    if (s.refused.empty() && !s.region.empty() && s.core == shells.front().core)
      shells.push_back(std::move(s));
  }
}

// choose_shells as the settings say; `near_plan` as choose_first's.
std::vector<ShellPlan> shells_as_set(const TriangleMesh& mesh, const Analysis& a,
                                     const LayerParams& p, const ShellChoice& c,
                                     ShellPlan* near_plan = nullptr) {
  std::vector<ShellPlan> shells;
  shells.push_back(choose_first(mesh, a, p, c, near_plan));
  add_further(mesh, a, p, c, shells);
  return shells;
}

}  // namespace

std::vector<ShellPlan> choose_shells(const TriangleMesh& mesh, const Analysis& a,
                                     const LayerParams& p, const ShellChoice& c) {
  ShellPlan near;  // choose_first's plan of the group near the largest patch, if it made one
  std::vector<ShellPlan> shells = shells_as_set(mesh, a, p, c, &near);
  // A shell banded over more than half of its patches is worth its bands (their print time,
  // and the slab over the whole part, 2.6 s of the bunny's 5.5 s slice) only where shells
  // over the regions apart, each banded less, leave a good part of it planar: the bunny's four
  // cover 86 % of its curved area (82.2 % of the top within 0.03 mm against the banded one's
  // 82.9 %, in 2.9 s against 5.5), two reliefs' two all of it; the ankle base's inner ring
  // alone 57 % (72 % against 81 %), the ornament's cap 52 % (53 % against 70 %).
  // With one shell at most (through another slicer: its one run prints no shell that the part
  // stands above, banded or not), there is nothing to weigh (the bunny's banded plan, dropped
  // for its size, was planned three times).
  constexpr double kBandedShare = 0.5, kCovered = 0.8;
  if (const ShellPlan& first = shells.front(); c.most < 2 || !first.refused.empty() ||
                                               first.banded <= kBandedShare ||
                                               p.shell_max_banded <= kBandedShare)
    return shells;
  auto area = [&](const std::vector<ShellPlan>& plans) {
    double sum = 0;
    for (const ShellPlan& s : plans)
      for (int i : s.patches) sum += a.patches[static_cast<std::size_t>(i)].area;
    return sum;
  };
  // Large rasters go before the others are planned (the bunny's H and slack over its whole
  // footprint: 32 MB of the slice's peak), planned again should they win; small ones stay (the
  // ornament's 5 MB: planning them again took 0.5 s of a 2.7 s slice).
  constexpr std::size_t kLargest = 16u << 20;  // bytes
  std::size_t bytes = 0;
  for (const ShellPlan& s : shells)
    bytes += 8 * (s.top.h.size() + s.slack.h.size()) + s.region.in.size();
  const double banded_area = area(shells);
  const bool dropped = bytes > kLargest;
  LayerParams less = p;
  less.shell_max_banded = kBandedShare;
  // The shells at shell_max_banded 0.5. The first over all the patches is refused there for
  // its bands, and choose_first then takes the group near the largest patch when that plans:
  // as planned beside it (only its bands depend on the limit), not planned again (both took
  // the bunny 0.33 s a time).
  std::vector<ShellPlan> apart;
  if (const ShellPlan& first = shells.front(); first.narrowed.empty() && !near.top.empty() &&
                                               near.refused.empty() &&
                                               near.banded <= kBandedShare) {
    apart.push_back(narrowed(std::move(near), curved_among(a, c.among),
                             banded_refusal(first.banded, first.stands_at, kBandedShare)));
    if (dropped) shells = {};
    add_further(mesh, a, less, c, apart);
  } else {
    near = {};
    if (dropped) shells = {};
    apart = shells_as_set(mesh, a, less, c);
  }
  const double covered = apart.front().refused.empty() ? area(apart) / banded_area : 0;
  if (covered < kCovered) return dropped ? (apart = {}, shells_as_set(mesh, a, p, c)) : shells;
  // Its notice names the setting the user did not set: say what was weighed instead.
  char instead[80];
  std::snprintf(instead, sizeof instead, "shells apart follow %.0f %% of its area", 100 * covered);
  std::string& why = apart.front().narrowed;
  if (const auto k = why.find("shell_max_banded 0.50"); k != std::string::npos)
    why.replace(k, std::string("shell_max_banded 0.50").size(), instead);
  return apart;
}

std::vector<ShellPlan> choose_shells_beside(const TriangleMesh& mesh, const Analysis& a,
                                            const LayerParams& p, const std::vector<int>& stacked,
                                            std::vector<int>& rest, std::string& why,
                                            const Context* cancel) {
  rest.clear(), why.clear();
  double curved = 0, left = 0;
  for (int i : curved_among(a, {})) {
    const double area = a.patches[static_cast<std::size_t>(i)].area;
    curved += area;
    if (std::find(stacked.begin(), stacked.end(), i) == stacked.end())
      rest.push_back(i), left += area;
  }
  // Too little left to be worth a core of thinner layers (h_c) under the whole part.
  constexpr double kLeast = 0.05;
  if (rest.empty() || left < kLeast * curved) return rest.clear(), std::vector<ShellPlan>{};
  ShellChoice c;
  c.among = rest, c.even_core = true, c.cancel = cancel;
  std::vector<ShellPlan> shells = choose_shells(mesh, a, p, c);
  const ShellPlan& first = shells.front();
  if (!first.refused.empty())
    why = first.refused;
  else if (first.core.size() < 3)
    why = "no room for a core under it";
  else if (std::any_of(shells.begin(), shells.end(),
                       [](const ShellPlan& s) { return s.region.empty(); }))
    why = "the part stands nowhere above it, so it would cover the stacks too";
  if (!why.empty()) shells.clear();
  return shells;
}

}  // namespace nonplanar::layers

namespace nonplanar {

ShellSummary summarize_shell(const TriangleMesh& mesh, const Analysis& a, const LayerParams& p,
                             const std::vector<int>& stacked) {
  ShellSummary s;
  std::vector<layers::ShellPlan> plans;
  if (stacked.empty()) {
    plans = layers::choose_shells(mesh, a, p);
    s.refused = plans.front().refused;
  } else {
    std::vector<int> rest;
    plans = layers::choose_shells_beside(mesh, a, p, stacked, rest, s.refused);
  }
  if (plans.empty() || !s.refused.empty()) return s;
  const layers::ShellPlan& plan = plans.front();
  s.narrowed = plan.narrowed;
  for (const layers::ShellPlan& q : plans) {
    s.patches.insert(s.patches.end(), q.patches.begin(), q.patches.end());
    s.layers = std::max(s.layers, q.N);
    s.thickness = std::max(s.thickness, q.t);
  }
  s.shells = static_cast<int>(plans.size());
  s.core_layers = plan.core.size() - 1;
  return s;
}

}  // namespace nonplanar
