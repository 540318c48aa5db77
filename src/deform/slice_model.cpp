// The pipeline (DESIGN.md §2): every stage is a free function; this only chains them and
// checks the result against DESIGN.md §3 before anyone writes it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>

#include "deform/gate_zones.hpp"
#include "deform/shell_engine.hpp"
#include "deform/shell_toolpaths.hpp"
#include "layers/banded_field.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/pipeline.hpp"
#include "slice/external_engine.hpp"

namespace nonplanar {

SliceJob make_job(const PrintConfig& print, double max_angle_deg) {
  SliceJob j;
  j.print = print;
  j.analysis.max_angle_deg = max_angle_deg;
  j.layers.layer_height = print.slice.layer_height;
  j.layers.first_layer_height = print.slice.first_layer_height;
  j.layers.max_angle_deg = max_angle_deg;
  j.layers.min_layer_height = print.min_layer_height > 0
                                  ? print.min_layer_height
                                  : std::min(j.analysis.min_layer_height, print.slice.layer_height);
  j.layers.max_layer_height =
      print.max_layer_height > 0
          ? print.max_layer_height
          : std::min(print.paths.nozzle_diameter,
                     std::max(1.5 * print.slice.layer_height,
                              std::min(0.75 * print.paths.nozzle_diameter, 0.3)));
  j.analysis.min_layer_height = j.layers.min_layer_height;
  // A layer steeper than the nozzle's outer wall drags the wall through the layer under it
  // (DESIGN.md §3): the cone bounds the slope, for the facets painted and the layers alike.
  const double cone = print.toolhead.cone_angle_deg;
  if (cone < max_angle_deg) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "max_angle lowered from %.1f to %.1f deg: the nozzle's cone "
                  "(nozzle_cone_angle) is no steeper",
                  max_angle_deg, cone);
    j.notices.emplace_back(buf);
    j.analysis.max_angle_deg = j.layers.max_angle_deg = cone;
  }
  j.layers.toolhead = print.toolhead;
  j.map_back.tip_radius = print.toolhead.tip_radius;
  j.map_back.travel_lift = travel_lift(print.gcode.retract_lift);
  j.check = check_params(print, j.layers.max_angle_deg);
  return j;
}

namespace {

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
using Violation = std::function<bool(const Vec3&, const char*)>;
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
  cp.collisions_only = true;
  // Only where a curved layer is within the head's reach (gate_zones.hpp): on the bunny that
  // skipped most of 24 million extrusion samples.
  GateZones zones = banded ? gate_zones(*banded, cp.toolhead.reach()) : GateZones{};
  zones.find_last_layers(r.layers);
  cp.collision_zones = zones.query;
  auto figures = check_print(moves_from_toolpaths(r.layers, job.print.gcode,
                                                  [&](const ExtrusionPath& p, int li) {
                                                    return !banded || zones.may_matter(p, li);
                                                  }),
                             nullptr, cp, ctx);
  if (!figures) return figures.error();
  r.collisions = figures->collisions;
  if (figures->collisions > 0)
    for (const Vec3& p : figures->collision_points)
      if (!violation(p, "an extrusion would hit earlier layers")) return false;
  return true;
}

// Our header on top of the engine's file: what was curved, and what was forced on it.
// shell_first_layer > 0: the shell route's, with its core's first layer height (mm).
std::string engine_header(const SliceJob& job, const std::vector<std::string>& header,
                          double shell_first_layer) {
  std::string head = "; generated by nonplanar 0.1.0 with ";
  head += job.engine.engine == Engine::orcaslicer ? "OrcaSlicer" : "PrusaSlicer";
  head += " as the planar engine\n";
  for (const std::string& h : header) head += "; " + h + "\n";
  for (const std::string& f : engine_forced_settings(job.engine, job.print))
    head += "; engine setting: " + f + "\n";
  if (shell_first_layer > 0)
    for (const std::string& f : engine_shell_settings(shell_first_layer))
      head += "; engine setting: " + f + "\n";
  return head;
}

// The external engine's route: it slices `to_slice` (the normalised mesh, or the mesh when
// nothing is curved) and its G-code is mapped back through the plan's field (the planar field
// when nothing is curved, which keeps every point). Fills r.gcode, r.layers and the header.
Expected<bool> slice_with_engine(const TriangleMesh& to_slice, const SliceJob& job, SliceResult& r,
                                 const Context& ctx) {
  auto text = run_engine(job.engine, to_slice, job.print, ctx);
  if (!text) return text.error();
  const auto planar = planar_field(job.layers);
  const LayerField& field = r.nonplanar ? *r.plan.field : *planar;
  auto mapped = map_foreign_gcode(*text, field, job.map_back, ctx);
  if (!mapped) {
    Error e = mapped.error();
    e.message = "engine G-code, " + e.message;
    return e;
  }
  r.layers = std::move(mapped->layers);
  r.gcode = engine_header(job, r.header, 0) + mapped->text;
  return true;
}

// One attempt with the patches not in `excluded`. When no stack can be built and `deferred` is
// given, it is set and the result is returned unsliced (the caller tries a shell first). On a limit
// violation inside a curved band, every such band's patch and what it broke are added to *offenders
// (the caller retries without them; all thickness and slope offenders of one attempt are found at
// once). Analysis and fitted surfaces: computed once, shared by every attempt.
struct Prepared {
  Analysis analysis;
  std::vector<SurfaceFit> fits;
  std::vector<int> ids;       ///< patch of each fit
  mutable StackCache stacks;  ///< each patch's stack is built once across the attempts
};

Expected<SliceResult> attempt(const TriangleMesh& mesh, const SliceJob& job, const Prepared& pre,
                              const std::vector<int>& excluded,
                              std::vector<std::pair<int, std::string>>* offenders, bool* deferred,
                              const Context& ctx) {
  offenders->clear();
  if (deferred) *deferred = false;
  SliceResult r;
  r.header.push_back(std::string("mode: ") + (job.planar_only ? "planar" : "non-planar"));
  if (!job.planar_only) {
    char buf[160];
    std::snprintf(
        buf, sizeof buf, "curved layers: h_min %.3f mm, h_max %.3f mm, max_angle %.1f deg",
        job.layers.min_layer_height, job.layers.max_layer_height, job.layers.max_angle_deg);
    r.header.push_back(buf);
    r.header.push_back("toolhead: " + job.layers.toolhead.describe());
  }
  const TriangleMesh* to_slice = &mesh;
  TriangleMesh normalized;
  if (!job.planar_only) {
    // The surfaces of the patches not excluded (analysis and fits do not depend on which).
    const Analysis* a = &pre.analysis;
    std::vector<SurfaceFit> fits;
    std::vector<int> ids;
    for (std::size_t i = 0; i < pre.ids.size(); ++i)
      if (std::find(excluded.begin(), excluded.end(), pre.ids[i]) == excluded.end())
        fits.push_back(pre.fits[i]), ids.push_back(pre.ids[i]);
    auto plan = plan_layers(mesh, *a, fits, ids, job.layers, pre.stacks, ctx);
    if (!plan) return plan.error();
    r.plan = std::move(*plan);
    for (const auto& fb : r.plan.fallbacks)
      r.notices.push_back("patch " + std::to_string(fb.patch) + " printed planar: " + fb.reason);
    if (r.plan.stacks.empty()) {
      std::size_t candidates = 0;
      for (const Patch& p : a->patches) candidates += p.needs_nonplanar();
      r.notices.push_back(candidates == 0 ? "no surface needs non-planar layers; slicing planar"
                                          : "no patch can be printed non-planar; slicing planar");
      // The caller may print it as a shell instead (try_shell): slice planar only if not.
      if (deferred && candidates > 0) return *deferred = true, r;
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
  if (job.engine.engine != Engine::builtin) {
    auto sliced = slice_with_engine(*to_slice, job, r, ctx);
    if (!sliced) return sliced.error();
  } else {
    auto sliced = slice_mesh(*to_slice, job.print.slice, ctx);
    if (!sliced) return sliced.error();
    auto paths = make_toolpaths(*sliced, job.print.paths, ctx);
    if (!paths) return paths.error();
    if (!r.nonplanar) {
      r.layers = std::move(*paths);
    } else {
      auto mapped = map_toolpaths_back(*paths, *r.plan.field, job.map_back, ctx);
      if (!mapped) return mapped.error();
      r.layers = std::move(*mapped);
    }
  }
  // The band a location belongs to: the one whose blend weight β is largest there (the
  // stacks and the field's bands are in the same order).
  const auto* banded = dynamic_cast<const layers::BandedField*>(r.plan.field.get());
  auto band_at = [&](const Vec3& p) {
    if (!banded) return -1;
    int best = -1;
    double top = 0;
    for (std::size_t b = 0; b < banded->bands().size(); ++b) {
      const double beta = banded->bands()[b].beta(p.x(), p.y());
      if (beta > top) top = beta, best = r.plan.stacks[b].patch;
    }
    return best;
  };
  // A violation in a curved band marks that band (true: go on looking); elsewhere it is a
  // bug, reported as an error.
  std::optional<Error> fatal;
  auto violation = [&](const Vec3& p, const char* what) {
    char buf[240];
    std::snprintf(buf, sizeof buf, "%s at (%.2f, %.2f, %.2f)", what, p.x(), p.y(), p.z());
    const int band = r.nonplanar ? band_at(p) : -1;
    if (band < 0) {
      fatal = Error{Status::internal_error, std::string("safety check: ") + buf};
      return false;
    }
    for (const auto& o : *offenders)
      if (o.first == band) return true;
    offenders->emplace_back(band, buf);
    return true;
  };
  auto ok = gate(r, job, banded, violation, ctx);
  if (!ok) return ok.error();
  if (!*ok) return *fatal;
  return r;
}

// A part whose whole top is one patch no stack over a plane could follow (the result of the
// attempts is planar): curved shell layers over a planar core (layers/shell_plan.hpp) if the
// gate passes them. Empty when the part is not of that kind or the shell breaks a limit (a
// notice then says why).
Expected<std::optional<SliceResult>> try_shell(const TriangleMesh& mesh, const SliceJob& job,
                                               const Analysis& analysis, SliceResult& planar,
                                               const Context& ctx) {
  // All the patches that need curved layers, taken as one top (the CurviSlicer airfoil's top
  // is two, split at a crease); failing that, the largest alone.
  const layers::ShellPlan plan = layers::choose_shell(mesh, analysis, job.layers);
  if (plan.patches.empty()) return std::optional<SliceResult>{};
  std::string name = "patch";
  if (plan.patches.size() > 1) name += "es";
  for (std::size_t k = 0; k < plan.patches.size(); ++k)
    name += (k ? ", " : " ") + std::to_string(plan.patches[k]);
  if (!plan.refused.empty()) {
    if (plan.refused != layers::kNotOnTop)
      planar.notices.push_back(name + " not printed as a shell: " + plan.refused);
    return std::optional<SliceResult>{};
  }
  SliceResult r;
  if (job.engine.engine == Engine::builtin) {
    auto paths = shell_toolpaths(mesh, plan, job.print, ctx);
    if (!paths) return paths.error();
    r.layers = std::move(*paths);
  } else {
    auto printed = shell_with_engine(mesh, plan, job, ctx);
    if (!printed && printed.error().status == Status::unsupported) {
      planar.notices.push_back(name + " not printed as a shell: " + printed.error().message);
      return std::optional<SliceResult>{};
    }
    if (!printed) return printed.error();
    r.layers = std::move(printed->layers);
    r.gcode = std::move(printed->gcode);
  }
  r.header = planar.header;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "%s: a shell of %d curved layers of %.2f mm over %zu planar core layers",
                name.c_str(), plan.N, plan.t, plan.core.size() - 1);
  r.header.push_back(buf);
  for (const std::string& n : planar.notices) {
    const bool about_shell = std::any_of(plan.patches.begin(), plan.patches.end(), [&](int i) {
      return n.rfind("patch " + std::to_string(i) + " ", 0) == 0;
    });
    if (!about_shell && n.rfind("no patch can", 0) != 0) r.notices.push_back(n);
  }
  r.notices.push_back(name + ": curved shell over a planar core (no stack over a plane fits it)");
  if (!r.gcode.empty()) r.gcode = engine_header(job, r.header, plan.core.at(1)) + r.gcode;
  r.nonplanar = true;
  r.shell_layers = plan.N;
  std::string breach;
  auto ok = gate(
      r, job, nullptr,
      [&](const Vec3& p, const char* what) {
        char b[200];
        std::snprintf(b, sizeof b, "%s at (%.2f, %.2f, %.2f)", what, p.x(), p.y(), p.z());
        breach = b;
        return false;
      },
      ctx);
  if (!ok) return ok.error();
  if (!*ok) {
    planar.notices.push_back(name + " not printed as a shell: " + breach);
    return std::optional<SliceResult>{};
  }
  return std::optional<SliceResult>(std::move(r));
}

}  // namespace

namespace {

// slice_model's rounds: attempts, retries without the patches that broke a limit, shells.
Expected<SliceResult> slice_rounds(const TriangleMesh& mesh, const SliceJob& job,
                                   const Context& ctx) {
  Prepared pre;
  if (!job.planar_only) {
    auto a = analyze(mesh, job.analysis, ctx);
    if (!a) return a.error();
    pre.analysis = std::move(*a);
    auto fits = fit_patches(mesh, pre.analysis, job.fit, {}, &pre.ids, ctx);
    if (!fits) return fits.error();
    pre.fits = std::move(*fits);
  }
  std::vector<int> excluded;
  std::vector<std::string> dropped;
  std::vector<std::pair<int, std::string>> offenders;
  for (int round = 0; round < 8; ++round) {
    // OrcaSlicer prints no shells (its command line cannot take our layer boundaries): with
    // it, a part without stacks slices planar at once.
    bool deferred = false;
    auto r = attempt(mesh, job, pre, excluded, &offenders,
                     job.engine.engine != Engine::orcaslicer ? &deferred : nullptr, ctx);
    if (!r) return r;
    if (deferred) {
      // No curved stack: a shell, or else the same attempt sliced planar (its stacks cached).
      r->notices.insert(r->notices.begin(), dropped.begin(), dropped.end());
      auto shell = try_shell(mesh, job, pre.analysis, *r, ctx);
      if (!shell) return shell.error();
      if (*shell) return std::move(**shell);
      const std::vector<std::string> notices = std::move(r->notices);
      r = attempt(mesh, job, pre, excluded, &offenders, nullptr, ctx);
      if (!r) return r;
      r->notices = notices;
      return r;
    }
    if (offenders.empty()) {
      r->notices.insert(r->notices.begin(), dropped.begin(), dropped.end());
      return r;
    }
    // A stack that met every limit on its own grid broke one in the final paths: print
    // that patch planar rather than refuse the part.
    // A patch that fell back in this attempt stays planar too. Its blend may only have
    // failed beside a band dropped now, so it could pass next time; but each such comeback
    // costs a whole attempt, and on the bunny both comebacks (patches 5 and 13) then collided.
    for (const PlanarFallback& fb : r->plan.fallbacks) {
      excluded.push_back(fb.patch);
      dropped.push_back("patch " + std::to_string(fb.patch) + " printed planar: " + fb.reason);
    }
    for (const auto& [patch, why] : offenders) {
      excluded.push_back(patch);
      dropped.push_back("patch " + std::to_string(patch) + " printed planar: in its final paths " +
                        why);
    }
  }
  return Error{Status::internal_error, "safety check: still failing after dropping 8 patches"};
}

}  // namespace

Expected<SliceResult> slice_model(const TriangleMesh& mesh, const SliceJob& job,
                                  const Context& ctx) {
  auto r = slice_rounds(mesh, job, ctx);
  if (!r) return r;
  if (auto e = nothing_to_print(*r, mesh)) return *e;
  r->notices.insert(r->notices.begin(), job.notices.begin(), job.notices.end());
  return r;
}

}  // namespace nonplanar
