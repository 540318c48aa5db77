// Notation as in layers/shell_plan.hpp: H the top, N shell layers of thickness t, B = H − N·t,
// a the reach; the core's layer with top z is printed where z <= B + a.
#include "engine/shell_engine.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <future>
#include <map>
#include <optional>

#include "engine/external_engine.hpp"
#include "nonplanar/deform.hpp"

namespace nonplanar {
namespace {

// The core's layers cut back under the shell: kept where H − N·t + a − z >= 0 within `inset`
// all round. The built-in core draws its perimeters inside the kept region, so its beads end
// half a width short of the cut; cut lines of the engine's paths end on it. With the bead on
// the cut, the shell's lowest layer a tip's radius downhill is r·tan θ lower, and on the
// wing's 27° side that entered the core by 0.12 mm, over the collision test's h / 2.
class CoreClip final : public LayerClip {
 public:
  CoreClip(const layers::ShellPlan& p, double inset) : p_(p), inset_(inset), slopes_(p.top) {
    const auto [lo, hi] = std::minmax_element(p.top.h.begin(), p.top.h.end());
    lo_ = *lo, hi_ = *hi;
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4;
      around_[static_cast<std::size_t>(k)] = Vec2(inset_ * std::cos(a), inset_ * std::sin(a));
    }
  }
  Cover cover(double z) const override {
    const double level = p_.core_level(z);
    return level <= lo_ ? Cover::all : level > hi_ ? Cover::none : Cover::some;
  }
  // The least over the point and 8 around it at the inset: continuous, as the clip needs.
  double margin(double x, double y, double z) const override {
    double h = p_.top.height(x, y);
    for (const Vec2& o : around_) h = std::min(h, p_.top.height(x + o.x(), y + o.y()));
    return h - p_.core_level(z);
  }
  // The least of H at 9 points is no steeper than H over the box they sweep.
  double slope_bound(const Vec2& lo, const Vec2& hi, double) const override {
    return slopes_.over(lo - Vec2::Constant(inset_), hi + Vec2::Constant(inset_));
  }

 private:
  const layers::ShellPlan& p_;
  double inset_ = 0;
  layers::TopSlopeBound slopes_;
  std::array<Vec2, 8> around_;  ///< the 8 points at the inset, from the centre
  double lo_ = 0, hi_ = 0;
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

// The core: the whole mesh sliced on the plan's boundaries (its skins then sit under the real
// top, so the shell counts as their cover), each layer cut back under the shell. Reports no
// progress: it runs beside the shell's run.
Expected<ForeignGcode> core_with_engine(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                        const EngineRoute& job, const Context& ctx) {
  EngineRun core_run;
  core_run.layer_tops.assign(plan.core.begin() + 1, plan.core.end());
  auto core_text = run_engine(job.engine, mesh, job.print, ctx, core_run, job.early);
  if (!core_text) return core_text.error();
  return map_shell_core(*core_text, plan, job, ctx);
}

}  // namespace

Expected<ForeignGcode> map_shell_core(std::string_view core_text, const layers::ShellPlan& plan,
                                      const EngineRoute& job, const Context& ctx,
                                      std::vector<char> others) {
  const CoreClip clip(plan, 0.5 * job.print.paths.perimeter_width);
  ForeignMapOptions core_opt;
  core_opt.clip = &clip;
  core_opt.planar_lines = std::move(others);
  const auto planar = planar_field(job.layers);
  auto core = map_foreign_gcode(core_text, *planar, job.map_back, ctx, core_opt);
  if (!core) {
    Error e = core.error();
    e.message = "engine G-code (core), " + e.message;
    return e;
  }
  // An engine that ignored the profile would leave the stairs other than planned, and the
  // shell's lowest layer thicker or thinner than the gate believes: refuse such a core. A
  // layer of supports alone (PrusaSlicer prints them on layers of their own, a contact
  // distance under the part) holds no stair.
  for (const LayerToolpaths& L : core->layers) {
    const bool part = std::any_of(L.paths.begin(), L.paths.end(), [](const ExtrusionPath& p) {
      return p.role != ExtrusionRole::support && p.role != ExtrusionRole::skirt && p.object == 0;
    });
    const auto near = std::lower_bound(plan.core.begin(), plan.core.end(), L.max_z - 2e-3);
    if (part && (near == plan.core.end() || *near > L.max_z + 2e-3)) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    "the core has a layer at z = %.3f mm, not on the planned boundaries: the "
                    "slicer did not follow the 3MF's layer-height profile",
                    L.max_z);
      return Error{Status::unsupported, buf};
    }
  }
  return core;
}

Expected<EngineShell> shell_with_engine(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                        const EngineRoute& job, const Context& ctx) {
  // One engine run cannot stop its core part-way for the shell and go on after it.
  if (!plan.region.empty())
    return Error{Status::unsupported,
                 "through an engine, a shell prints only where the part stands nowhere above "
                 "its top (the built-in engine prints this one)"};
  // The two runs side by side: the engine's own run is partly serial (on the wing the core's
  // took 0.40 s, the shell's 0.21, one after the other). A thread of its own, not a TBB task:
  // it mostly waits for the engine, and must not hold a worker the stages below would use.
  Context quiet;
  quiet.cancel_flag = ctx.cancel_flag;
  ctx.progress("engine", 0);
  auto core_job =
      std::async(std::launch::async, [&] { return core_with_engine(mesh, plan, job, quiet); });
  // The shell: the normalised mesh's slab 0 <= ζ <= N·t.
  const layers::ShellField field(plan);
  auto normalized = normalize_mesh(mesh, field, shell_normalize_params(mesh), ctx);
  EngineRun shell_run;
  shell_run.slab_layer_height = plan.t;
  Expected<std::string> shell_text =
      normalized
          ? run_engine(job.engine, cut_below(normalized->mesh, 0.0), job.print, ctx, shell_run)
          : Expected<std::string>(normalized.error());
  auto core = core_job.get();  // (its error first, as when the runs went one after the other)
  if (!core) return core.error();
  if (!shell_text) return shell_text.error();
  ctx.progress("core", 1.0);
  return join_shell(std::move(*core), *shell_text, plan, 0.0, job,
                    "the shell's curved layers, from the engine's second run", ctx);
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
