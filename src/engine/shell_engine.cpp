// Notation as in layers/shell_plan.hpp: H the top, N shell layers of thickness t, B = H − N·t,
// a the reach; the core's layer with top z is printed where z <= B + a.
#include "engine/shell_engine.hpp"

#include <malloc.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <span>

#include "core/ahead_run.hpp"
#include "core/sanitizers.hpp"
#include "engine/external_engine.hpp"
#include "engine/shell_split.hpp"
#include "engine/shell_toolpaths.hpp"
#include "layers/height_contour.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {
namespace {

// The core's layers cut back under the shells: kept where H − N·t + a − z >= 0 within `inset`
// all round, or (a shell the part stands above somewhere) outside its region R. The built-in
// core draws its perimeters inside the kept region, so its beads end half a width short of the
// cut; cut lines of the engine's paths end on it. With the bead on the cut, the shell's lowest
// layer a tip's radius downhill is r·tan θ lower, and on the wing's 27° side that entered the
// core by 0.12 mm, over the collision test's h / 2.
class CoreClip final : public LayerClip {
 public:
  CoreClip(std::span<const layers::ShellPlan> plans, double inset) : inset_(inset) {
    for (const layers::ShellPlan& p : plans) {
      const auto [lo, hi] = std::minmax_element(p.top.h.begin(), p.top.h.end());
      shells_.push_back({&p, layers::TopSlopeBound(p.top),
                         p.region.empty() ? layers::NodeDistance{} : signed_distance(p.region), *lo,
                         *hi});
    }
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4;
      around_[static_cast<std::size_t>(k)] = Vec2(inset_ * std::cos(a), inset_ * std::sin(a));
    }
  }
  Cover cover(double z) const override {
    bool all = true, none = true;
    for (const Shell& s : shells_) {
      const double level = s.plan->core_level(z);
      all = all && level <= s.lo;
      none = none && level > s.hi && s.plan->region.empty();
    }
    return all ? Cover::all : none ? Cover::none : Cover::some;
  }
  // The least over the shells that cut the layer of: the least of H − level over the point
  // and 8 around it at the inset, and with a region the larger of that and cell·D (D R's
  // signed distance, > 0 outside): continuous, as the clip needs, and < 0 just where the
  // built-in core is cut. Outside R, or above H's highest point, cell·D alone says the same,
  // and its size is how far R is: a move away from it is looked at once.
  double margin(double x, double y, double z) const override {
    double m = std::numeric_limits<double>::infinity();
    for (const Shell& s : shells_) {
      const layers::ShellPlan& p = *s.plan;
      const double level = p.core_level(z);
      if (level <= s.lo) continue;  // H >= level: nothing cut
      const double d = s.distance.empty() ? 0.0 : s.distance.cell * s.distance.value(x, y);
      if (!s.distance.empty() && (d >= 0 || level > s.hi)) {
        m = std::min(m, d);
        continue;
      }
      double h = p.top.height(x, y);
      for (const Vec2& o : around_) h = std::min(h, p.top.height(x + o.x(), y + o.y()));
      m = std::min(m, s.distance.empty() ? h - level : std::max(h - level, d));
    }
    return std::isinf(m) ? 1e3 : m;
  }
  // The least of H at 9 points is no steeper than H over the box they sweep; cell·D no
  // steeper than √2.
  double slope_bound(const Vec2& lo, const Vec2& hi, double z) const override {
    double b = 0;
    for (const Shell& s : shells_) {
      const double level = s.plan->core_level(z);
      if (level <= s.lo) continue;
      if (s.distance.empty() || level <= s.hi)
        b = std::max(b, s.slopes.over(lo - Vec2::Constant(inset_), hi + Vec2::Constant(inset_)));
      if (!s.distance.empty()) b = std::max(b, std::sqrt(2.0));
    }
    return b;
  }

 private:
  struct Shell {
    const layers::ShellPlan* plan;
    layers::TopSlopeBound slopes;
    layers::NodeDistance distance;  ///< R's, with a region
    double lo, hi;                  ///< H's range
  };
  std::vector<Shell> shells_;
  double inset_ = 0;
  std::array<Vec2, 8> around_;  ///< the 8 points at the inset, from the centre
};

}  // namespace

TriangleMesh cut_below(const TriangleMesh& mesh, double z0) {
  TriangleMesh out;
  std::vector<int> kept(mesh.vertices.size(), -1);
  std::map<std::pair<int, int>, int> cuts;  // edge (lower index first) → its cut vertex
  auto vertex = [&](int v) {
    if (kept[static_cast<std::size_t>(v)] < 0) {
      kept[static_cast<std::size_t>(v)] = static_cast<int>(out.vertices.size());
      out.vertices.push_back(mesh.vertices[static_cast<std::size_t>(v)]);
    }
    return kept[static_cast<std::size_t>(v)];
  };
  auto cut = [&](int a, int b) {
    if (a > b) std::swap(a, b);
    auto [it, fresh] = cuts.try_emplace({a, b}, 0);
    if (fresh) {
      const Vec3& p = mesh.vertices[static_cast<std::size_t>(a)];
      const Vec3& q = mesh.vertices[static_cast<std::size_t>(b)];
      Vec3 c = p + (z0 - p.z()) / (q.z() - p.z()) * (q - p);
      c.z() = z0;
      it->second = static_cast<int>(out.vertices.size());
      out.vertices.push_back(c);
    }
    return it->second;
  };
  for (const auto& f : mesh.faces) {
    // The face's polygon above z0 (a vertex on z0 counts as above), in its own order.
    std::array<int, 4> poly{};
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const int a = f[static_cast<std::size_t>(k)], b = f[static_cast<std::size_t>((k + 1) % 3)];
      const bool in_a = mesh.vertices[static_cast<std::size_t>(a)].z() >= z0;
      const bool in_b = mesh.vertices[static_cast<std::size_t>(b)].z() >= z0;
      if (in_a) poly[static_cast<std::size_t>(n++)] = vertex(a);
      if (in_a != in_b) poly[static_cast<std::size_t>(n++)] = cut(a, b);
    }
    for (int k = 1; k + 1 < n; ++k)
      out.faces.push_back(
          {poly[0], poly[static_cast<std::size_t>(k)], poly[static_cast<std::size_t>(k + 1)]});
  }
  return out;
}

namespace {

constexpr double kSameZ = 2e-3;  ///< mm: a file writes ;Z: to 3 decimals

bool on_boundary(const layers::ShellPlan& plan, double z) {
  const auto near = std::lower_bound(plan.core.begin(), plan.core.end(), z - kSameZ);
  return near != plan.core.end() && *near <= z + kSameZ;
}

Error off_plan(double z) {
  char buf[300];
  std::snprintf(buf, sizeof buf,
                "the core has a layer at z = %.3f mm, not on the planned boundaries: the slicer "
                "did not follow the 3MF's layer-height profile",
                z);
  return Error{Status::unsupported, buf};
}

// The engine's file, before it is split: a layer of the part's up to the core's last boundary
// off the planned ones (the split would refuse it as a slab off the plan's, which says less).
std::optional<Error> core_off_plan(const GcodeProgram& prog, const layers::ShellPlan& plan) {
  for (const GcodeMove& m : prog.moves) {
    if (!m.extruding() || m.layer < 0) continue;
    const double z = prog.layer_z[static_cast<std::size_t>(m.layer)];
    const ExtrusionRole role = role_from_name(m.type);
    if (z <= plan.core.back() + kSameZ && role != ExtrusionRole::support &&
        role != ExtrusionRole::skirt && !on_boundary(plan, z))
      return off_plan(z);
  }
  return std::nullopt;
}

}  // namespace

namespace {

// The core's G-code mapped and cut back under the shells (one core: plans[0]'s boundaries),
// with what `opt` says besides.
Expected<ForeignGcode> map_core(std::string core_text, std::span<const layers::ShellPlan> plans,
                                const EngineRoute& job, const Context& ctx, ForeignMapOptions opt) {
  const layers::ShellPlan& plan = plans.front();
  const CoreClip clip(plans, 0.5 * job.print.paths.perimeter_width);
  opt.clip = &clip;
  const auto planar = planar_field(job.layers);
  auto core = map_foreign_gcode_consuming(std::move(core_text), *planar, job.map_back, ctx, opt);
  if (!core) {
    Error e = core.error();
    e.message = "engine G-code (core), " + e.message;
    return e;
  }
  // An engine that ignored the profile would leave the stairs other than planned, and the
  // shell's lowest layer thicker or thinner than the gate believes: refuse such a core. A
  // layer of supports alone (PrusaSlicer prints them on layers of their own, a contact
  // distance under the part) holds no stair.
  for (std::size_t k = 0; k < core->layers.size(); ++k) {
    const LayerToolpaths& L = core->layers[k];
    if (!core->inserted.empty() && core->inserted[k]) continue;  // a shell's piece
    const bool part = std::any_of(L.paths.begin(), L.paths.end(), [](const ExtrusionPath& p) {
      return p.role != ExtrusionRole::support && p.role != ExtrusionRole::skirt && p.object == 0;
    });
    if (part && !on_boundary(plan, L.max_z)) return off_plan(L.max_z);
  }
  return core;
}

}  // namespace

Expected<ForeignGcode> map_shell_core(std::string core_text, const layers::ShellPlan& plan,
                                      const EngineRoute& job, const Context& ctx,
                                      std::vector<char> others) {
  ForeignMapOptions opt;
  opt.planar_lines = std::move(others);
  return map_core(std::move(core_text), std::span(&plan, 1), job, ctx, std::move(opt));
}

namespace {

// The box from just above z_s (the slab's first layer is sliced at z_s + t/2, the core's last
// below z_s) to over the top, 1 mm wider than the part: a support blocker there leaves the
// slicer nothing to support under the slab, whose underside floats over the part's top in the
// 3MF (on the rib, supports on printed 53 min of columns against 35 without).
TriangleMesh slab_blocker(const BoundingBox& part, double z_s) {
  const Vec3 lo(part.min.x() - 1, part.min.y() - 1, z_s + 0.01);
  const Vec3 hi(part.max.x() + 1, part.max.y() + 1, part.max.z() + 1);
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(),
                            k & 4 ? hi.z() : lo.z());
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

}  // namespace

Expected<ShellStack> shell_stack(const TriangleMesh& placed, const layers::ShellPlan& plan,
                                 const Context& ctx) {
  ShellStack out;
  const double z_s = plan.core.back();
  out.base = z_s + plan.t;
  const layers::ShellField field(plan, out.base);
  auto normalized = normalize_mesh(placed, field, shell_normalize_params(placed), ctx);
  if (!normalized) return normalized.error();
  const TriangleMesh slab = cut_below(normalized->mesh, z_s);
  out.mesh = placed;
  const int offset = static_cast<int>(out.mesh.vertices.size());
  out.mesh.vertices.insert(out.mesh.vertices.end(), slab.vertices.begin(), slab.vertices.end());
  out.mesh.faces.reserve(out.mesh.faces.size() + slab.faces.size());
  for (const auto& f : slab.faces)
    out.mesh.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  out.support_blocker = slab_blocker(bounding_box(out.mesh), z_s);
  out.layer_tops.assign(plan.core.begin() + 1, plan.core.end());
  for (int j = 1; j <= plan.N + 1; ++j) out.layer_tops.push_back(z_s + j * plan.t);
  return out;
}

Expected<EngineShell> shell_with_engine(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                        const EngineRoute& job, const Context& ctx) {
  // One engine run cannot stop its core part-way for the shell and go on after it: such a
  // shell's pieces go between the layers of a run of the part alone.
  if (!plan.region.empty())
    return Error{Status::internal_error,
                 "shell_with_engine: a shell the part stands above prints in pieces"};
  // One run of the part with the shell's slab above its core, split where the core ends, as
  // post-process splits the slicer's file of a prepared shell. Two runs side by side (the
  // core, and the slab alone) took the whole process 1.36 s of CPU on the wing, this one 1.08.
  auto stack = shell_stack(mesh, plan, ctx);
  if (!stack) return stack.error();
  ctx.progress("engine", 0);
  EngineRun run;
  run.layer_tops = std::move(stack->layer_tops);
  run.layer_height = plan.t;
  run.support_blockers = {std::move(stack->support_blocker)};
  auto text = run_engine(job.engine, stack->mesh, job.print, ctx, run, job.early);
  if (!text) return text.error();
  stack->mesh = TriangleMesh{};
  ctx.progress("core", 0);
  Expected<ShellSplit> split = [&]() -> Expected<ShellSplit> {
    const GcodeProgram prog = read_gcode_program(*text);
    if (auto e = core_off_plan(prog, plan)) return *e;
    return shell_split(prog, *text, {}, plan);
  }();
  if (!split) {
    // The engine's layers off the plan's: the part prints planar, saying why.
    Error e = split.error();
    if (e.status == Status::invalid_argument) e.status = Status::unsupported;
    return e;
  }
  std::string().swap(*text);
  auto core = map_shell_core(std::move(split->core), plan, job, ctx);
  if (!core) return core.error();
  ctx.progress("core", 1.0);
  return join_shell(std::move(*core), split->shell, plan, stack->base, job,
                    "the shell's curved layers, from the engine's layers above the core", ctx);
}

Expected<EngineShell> shell_pieces_with_engine(const TriangleMesh& mesh,
                                               std::vector<layers::ShellPlan>& plans,
                                               const EngineRoute& job, const Context& ctx) {
  const std::vector<double> tops(plans.front().core.begin() + 1, plans.front().core.end());
  // The shells' curved layers, cut into their slots, beside the engine's run of the core
  // once it has the part (not beside the part's text for it).
  using Slots = std::vector<std::vector<LayerToolpaths>>;
  auto slice_shells = [&](const Context& c) -> Expected<Slots> {
    std::vector<std::vector<LayerToolpaths>> shells;
    for (const layers::ShellPlan& plan : plans) {
      const std::vector<ExPolygon> R = layers::region_at_least(plan.region.as_top(), 0);
      auto paths = shell_curved_layers(mesh, plan, R, job.print, c);
      if (!paths) return paths.error();
      shells.push_back(std::move(*paths));
    }
    return shell_slots(shells, plans, tops);
  };
  std::optional<core::AheadRun<Expected<Slots>>> ahead;
  ctx.progress("engine", 0);
  EngineRun run;
  run.layer_tops = tops;
  run.handed_over = [&] {
    if (!ahead) ahead.emplace(ctx, slice_shells);
  };
  auto text = run_engine(job.engine, mesh, job.print, ctx, run, job.early);
  if (!text) return text.error();
  auto slots = ahead ? ahead->get() : slice_shells(ctx);
  if (!slots) return slots.error();
  for (layers::ShellPlan& plan : plans) plan.slack = {};  // (the slots are cut)
#if defined(__GLIBC__) && !defined(NONPLANAR_SHADOW_MEMORY)
  // The shells were sliced on a thread whose allocator arena keeps what they freed (their
  // normalised meshes, sections): handed back before the core is mapped.
  malloc_trim(0);
#endif
  ctx.progress("core", 0);
  // Slot k follows the core's layer k − 1: its pieces go before the engine's first layer above
  // that layer's top (a layer of supports alone in between, or the next core layer).
  ForeignMapOptions opt;
  std::size_t next = 1;
  opt.before_layer = [&](double z, const Vec3& nozzle) {
    std::vector<LayerToolpaths> out;
    Vec2 at = nozzle.head<2>();
    for (; next < slots->size() && z > tops[next - 1] + kSameZ; ++next)
      for (LayerToolpaths& part : (*slots)[next]) {
        order_piece(part, job.print.toolhead, at);
        out.push_back(std::move(part));
      }
    return out;
  };
  opt.filament_per_mm = [&](double w, double h) { return filament_per_mm(w, h, job.print.gcode); };
  opt.inserted_travel_speed = job.print.paths.travel_speed;
  auto core = map_core(std::move(*text), plans, job, ctx, std::move(opt));
  if (!core) return core.error();
  ctx.progress("core", 1.0);
  EngineShell out;
  out.layers = std::move(core->layers);
  out.gcode = core->take_text();
  return out;
}

namespace {

// Where the first move of a program's print that goes somewhere in XY goes (none without).
std::optional<Vec2> first_xy(std::string_view text) {
  const GcodeProgram prog = read_gcode_program(text);
  for (const GcodeMove& m : prog.moves)
    if (m.layer >= 0 && m.has_xy) return Vec2(m.to.head<2>());
  return std::nullopt;
}

}  // namespace

Expected<EngineShell> join_shell(ForeignGcode core, std::string_view shell_text,
                                 const layers::ShellPlan& plan, double base, const EngineRoute& job,
                                 const std::string& note, const Context& ctx) {
  const layers::ShellPathField path_field(plan, base);
  ctx.progress("map back", 0);
  ForeignMapOptions shell_opt;
  shell_opt.start = core.end_at;
  std::string entry;
  if (const auto over = first_xy(shell_text)) {
    double top = core.end_at.z();
    for (const LayerToolpaths& L : core.layers) top = std::max(top, L.max_z);
    top += job.map_back.travel_lift;
    char buf[160];
    std::snprintf(buf, sizeof buf, "G1 Z%.3f F%.0f\nG1 X%.3f Y%.3f F%.0f\n", top,
                  60 * std::min(job.print.paths.travel_speed, 20.0), over->x(), over->y(),
                  60 * job.print.paths.travel_speed);
    entry = buf;
    shell_opt.start = Vec3(over->x(), over->y(), top);
  }
  shell_opt.start_retracted = core.retracted;
  auto shell = map_foreign_gcode(shell_text, path_field, job.map_back, ctx, shell_opt);
  if (!shell) {
    Error e = shell.error();
    e.message = "engine G-code (shell), " + e.message;
    return e;
  }

  // Stitch: the core's start and print, the shell's print, the core's end.
  EngineShell out;
  out.gcode.reserve(core.start.size() + core.print.size() + shell->print.size() + core.end.size() +
                    256);
  out.gcode.append(core.start).append(core.print);
  out.gcode += "; nonplanar: " + note + "\n";
  out.gcode += entry;
  out.gcode += shell->relative_e_at_print ? "M83\n" : "M82\n";
  if (!shell->fan_at_print.empty()) out.gcode += shell->fan_at_print + "\n";
  char buf[64];
  if (!shell->relative_e_at_print) {
    std::snprintf(buf, sizeof buf, "G92 E%.5f\n", shell->e_at_print);
    out.gcode += buf;
  }
  out.gcode.append(shell->print);
  out.gcode += "; nonplanar: the core run's end G-code\n";
  out.gcode += core.relative_e_at_end ? "M83\n" : "M82\n";
  out.gcode.append(core.end);
  out.layers = std::move(core.layers);
  for (LayerToolpaths& L : shell->layers) out.layers.push_back(std::move(L));
  return out;
}

}  // namespace nonplanar
