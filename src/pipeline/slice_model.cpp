// The pipeline (DESIGN.md §2): every stage is a free function; this only chains them and
// checks the result against DESIGN.md §3 before anyone writes it.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>

#include "core/ahead_run.hpp"
#include "core/column_caster.hpp"
#include "core/sanitizers.hpp"
#include "engine/engine_route.hpp"
#include "engine/shell_engine.hpp"
#include "layers/banded_field.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/pipeline.hpp"
#include "pipeline/gate.hpp"

namespace nonplanar {

namespace {

Notice planar_notice(int patch, const std::string& why) {
  return {Notice::Kind::patch_planar, patch,
          "patch " + std::to_string(patch) + " printed planar: " + why};
}

// The curved area the patches cover, mm².
double area_of(const Analysis& a, const std::vector<int>& patches) {
  double sum = 0;
  for (int i : patches) sum += a.patches[static_cast<std::size_t>(i)].area;
  return sum;
}

// The stacks' patches.
std::vector<int> stacked_patches(const LayerPlan& plan) {
  std::vector<int> ids;
  for (const LayerStack& st : plan.stacks) ids.push_back(st.patch);
  return ids;
}

// Whether a shell could cover more than twice what the stacks do: all curved patches together
// must (shell_before_stacks then asks it of the shell it plans).
bool shell_may_cover_more(const Analysis& a, const LayerPlan& plan) {
  std::vector<int> curved;
  for (std::size_t i = 0; i < a.patches.size(); ++i)
    if (a.patches[i].needs_nonplanar()) curved.push_back(static_cast<int>(i));
  return area_of(a, curved) > 2 * area_of(a, stacked_patches(plan));
}

// One attempt with the patches not in `excluded`. When no stack can be built, or (with
// defer_small_stacks) the stacks cover less than half the curved patches' area, and `deferred`
// is given, it is set and the result is returned unsliced (the caller tries a shell first). On a
// limit violation inside a curved band, every such band's patch and what it broke are added to
// *offenders (the caller retries without them; all thickness and slope offenders of one attempt are
// found at once). Analysis and fitted surfaces: computed once, shared by every attempt.
struct Prepared {
  Analysis analysis;
  std::vector<SurfaceFit> fits;
  std::vector<int> ids;       ///< patch of each fit
  mutable StackCache stacks;  ///< each patch's stack is built once across the attempts
  /// The last plan and the patches it left out: an attempt sliced after its shell was refused
  /// plans exactly what the deferred one did (on the bunny through PrusaSlicer, 1.1 s of
  /// blend checks and field again).
  mutable std::optional<std::pair<std::vector<int>, LayerPlan>> last_plan;
  /// PrusaSlicer as the engine, loading while the layers are planned (the first plain run
  /// takes it: the stacks' normalised mesh, or the part when none is curved).
  EarlyEnginePtr engine;
};

// f(ctx), planned on a thread of idle priority (its loops on that thread) while PrusaSlicer
// slices a run handed to it ahead: the plan takes the cores the slicer leaves idle (on the
// bunny PrusaSlicer kept both busy for 2.2 s, then one for 1.8 s), not the slicer's.
template <class F>
auto planned(const Prepared& pre, const Context& ctx, F&& f) -> decltype(f(ctx)) {
  if (!engine_ahead(pre.engine.get())) return f(ctx);
  core::AheadRun<decltype(f(ctx))> run(ctx, std::forward<F>(f), core::Priority::idle);
  return run.get();
}

Expected<SliceResult> attempt(const TriangleMesh& mesh, const SliceJob& job, const Prepared& pre,
                              const std::vector<int>& excluded,
                              std::vector<std::pair<int, std::string>>* offenders, bool* deferred,
                              bool defer_small_stacks, const Context& ctx) {
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
    if (pre.last_plan && pre.last_plan->first == excluded) {
      r.plan = pre.last_plan->second;
    } else {
      auto plan = planned(pre, ctx, [&](const Context& c) {
        return plan_layers(mesh, *a, fits, ids, job.layers, pre.stacks, c);
      });
      if (!plan) return plan.error();
      r.plan = std::move(*plan);
      pre.last_plan.emplace(excluded, r.plan);
    }
    for (const auto& fb : r.plan.fallbacks) r.notices.push_back(planar_notice(fb.patch, fb.reason));
    if (r.plan.stacks.empty()) {
      std::size_t candidates = 0;
      for (const Patch& p : a->patches) candidates += p.needs_nonplanar();
      r.notices.push_back(candidates == 0
                              ? Notice{Notice::Kind::none_needed, -1,
                                       "no surface needs non-planar layers; slicing planar"}
                              : Notice{Notice::Kind::none_fit, -1,
                                       "no patch can be printed non-planar; slicing planar"});
      // The caller may print it as a shell instead (try_shell): slice planar only if not.
      if (deferred && candidates > 0) return *deferred = true, r;
    } else if (deferred && defer_small_stacks && shell_may_cover_more(*a, r.plan)) {
      return *deferred = true, r;  // the caller tries a shell over the largest patch first
    } else {
      auto n = normalize_mesh(mesh, *r.plan.field, {}, ctx);
      if (!n) return n.error();
      normalized = std::move(n->mesh);
      to_slice = &normalized;
      r.nonplanar = true;
      r.printed_curved = static_cast<int>(r.plan.stacks.size());
      char buf[160];
      for (const LayerStack& st : r.plan.stacks) {
        std::snprintf(buf, sizeof buf, "patch %d: %d curved layers from z = %.2f mm", st.patch,
                      st.layers, st.c);
        r.header.push_back(buf);
      }
    }
  }
  const EngineRoute route{job.engine, job.print, job.layers, job.map_back, pre.engine.get()};
  auto sliced = slice_with(*to_slice, r.nonplanar ? r.plan.field.get() : nullptr, route, ctx);
  if (!sliced) return sliced.error();
  r.layers = std::move(sliced->layers);
  // The header goes in front in the text's own room (take_text leaves some): a joined copy
  // held the whole print twice.
  r.gcode = std::move(sliced->gcode);
  if (!r.gcode.empty()) r.gcode.insert(0, engine_header(route, r.header, 0));
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

// "patch 3" or "patches 0, 2, 7": the patches of the shells, in order.
std::string patch_names(const std::vector<int>& patches) {
  std::string name = patches.size() > 1 ? "patches" : "patch";
  for (std::size_t k = 0; k < patches.size(); ++k)
    name += (k ? ", " : " ") + std::to_string(patches[k]);
  return name;
}

// The patches of every shell.
std::vector<int> shell_patches(const std::vector<layers::ShellPlan>& shells) {
  std::vector<int> all;
  for (const layers::ShellPlan& s : shells)
    all.insert(all.end(), s.patches.begin(), s.patches.end());
  return all;
}

// layers::choose_shells, one shell only for one slicer run (prepare); stopped when ctx is
// cancelled. Through an engine, a shell the part stands above prints as the built-in's does,
// its pieces between the engine's core layers (shell_pieces_with_engine).
layers::ShellChoice shell_choice(const SliceJob& job, const Context& ctx) {
  layers::ShellChoice c;
  c.most = job.one_run_shells ? 1 : 4;
  c.cancel = &ctx;
  // One run prints no shell the part stands above: such a plan is refused once its R is known
  // (the bunny's was planned in full, 3 s beside PrusaSlicer's run and 143 MB, then refused),
  // and the next one tried (the patches near the largest, the largest alone).
  if (job.one_run_shells) c.whole_only = kOneRunShellWhole;
  return c;
}
std::vector<layers::ShellPlan> shells_for(const TriangleMesh& mesh, const Analysis& a,
                                          const SliceJob& job, const Context& ctx) {
  return layers::choose_shells(mesh, a, job.layers, shell_choice(job, ctx));
}

// The header lines and notices of the shells printed (r's), from the planar attempt's.
void describe_shells(const std::vector<layers::ShellPlan>& shells, const std::string& why_shell,
                     const SliceResult& planar, SliceResult& r) {
  const std::vector<int> patches = shell_patches(shells);
  // The attempt's header, without its stacks' lines (the shell replaces them).
  for (const std::string& line : planar.header)
    if (line.rfind("patch ", 0) != 0) r.header.push_back(line);
  for (const layers::ShellPlan& s : shells) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "%s: a shell of %d curved layers of %.2f mm over %zu planar core layers",
                  patch_names(s.patches).c_str(), s.N, s.t, s.core.size() - 1);
    r.header.push_back(buf);
  }
  // What the planar attempt said of the shell's patches, and that no patch fits, is moot now;
  // but a setting that would let a stack fit (a stack follows the top more closely) is kept.
  for (const Notice& n : planar.notices) {
    const bool about_shell = n.kind == Notice::Kind::patch_planar &&
                             std::find(patches.begin(), patches.end(), n.patch) != patches.end();
    if (n.kind == Notice::Kind::none_fit || (about_shell && !n.names_a_fix)) continue;
    Notice kept = n;
    if (about_shell)  // not planar after all: the shell prints it
      kept.text = "patch " + std::to_string(n.patch) +
                  " has no stack: " + n.text.substr(std::min(n.text.size(), n.text.find(": ") + 2));
    r.notices.push_back(std::move(kept));
  }
  std::string left_out;
  for (const layers::ShellPlan& s : shells)
    if (!s.left_out.empty())
      left_out += "; " + (shells.size() > 1 ? patch_names(s.patches) + ": " : "") + s.left_out;
  if (!shells.front().narrowed.empty()) left_out += "; not " + shells.front().narrowed;
  r.notices.push_back(
      {Notice::Kind::shell, -1,
       patch_names(patches) +
           (shells.size() > 1 ? ": " + std::to_string(shells.size()) + " curved shells"
                              : ": curved shell") +
           " over a planar core (" + why_shell + ")" + left_out});
  for (const layers::ShellPlan& s : shells) r.shell_layers = std::max(r.shell_layers, s.N);
  r.printed_curved = static_cast<int>(patches.size());
}

// Curved shells over a planar core (layers/shell_plan.hpp) for a part no stack serves, or
// serves little, if the gate passes them. Empty when a shell is refused or breaks a limit (a
// notice then says why).
// `spent` is called once the shells are sliced, before the gate: their rasters are no longer
// needed then, unless the caller retries with one of them.
// `stacks`: curved stacks the core holds beside the shells (shells_beside_stacks), on the
// core's layers.
Expected<std::optional<SliceResult>> try_shell(const TriangleMesh& mesh, const SliceJob& job,
                                               std::vector<layers::ShellPlan>& shells,
                                               const std::string& why_shell, SliceResult& planar,
                                               const std::function<void()>& spent,
                                               EarlyEngine* early, const Context& ctx,
                                               const LayerPlan* stacks = nullptr) {
  const std::vector<int> patches = shell_patches(shells);
  if (patches.empty()) return std::optional<SliceResult>{};
  const layers::ShellPlan& plan = shells.front();
  const std::string name = patch_names(patches);
  auto refused = [&](const std::string& why) {
    return Notice{Notice::Kind::shell_refused, -1, name + " not printed as a shell: " + why};
  };
  if (!plan.refused.empty()) {
    planar.notices.push_back(refused(plan.refused));
    return std::optional<SliceResult>{};
  }
  // The slicer prints the core's layers, then the shell's above them: it cannot go back to
  // the core after the shell, as printing beside what stands above the top needs.
  if (job.one_run_shells && !plan.region.empty()) {
    planar.notices.push_back(refused(std::string(kOneRunShellWhole)));
    return std::optional<SliceResult>{};
  }
  SliceResult r;
  const EngineRoute route{job.engine, job.print, job.layers, job.map_back, early};
  const bool pieces = !plan.region.empty();  // (shell_with may spend the rasters)
  auto printed = shell_with(mesh, shells, route, ctx, stacks ? stacks->field.get() : nullptr);
  if (!printed && printed.error().status == Status::unsupported) {
    planar.notices.push_back(refused(printed.error().message));
    return std::optional<SliceResult>{};
  }
  if (!printed) return printed.error();
  r.layers = std::move(printed->layers);
  r.gcode = std::move(printed->gcode);
  describe_shells(shells, why_shell, planar, r);
  if (stacks) {
    for (const LayerStack& st : stacks->stacks) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "patch %d: %d curved layers from z = %.2f mm", st.patch,
                    st.layers, st.c);
      r.header.push_back(buf);
    }
    r.plan = *stacks;
    r.printed_curved += static_cast<int>(stacks->stacks.size());
  }
  // In the text's own room, as above (the bunny's 28.6 MB were held twice at the engine
  // route's peak: 168-172 MB against PrusaSlicer's 168).
  if (!r.gcode.empty()) r.gcode.insert(0, engine_header(route, r.header, plan.core.at(1), pieces));
  r.nonplanar = true;
  spent();
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
    planar.notices.push_back(refused(breach));
    return std::optional<SliceResult>{};
  }
  return std::optional<SliceResult>(std::move(r));
}

// The rasters of a shell sliced and not to be sliced again (on the bunny its four shells'
// were 80 MB, alive while the gate read the G-code).
void drop_rasters(layers::ShellPlan& s) {
  s.top = {}, s.region = {}, s.slack = {}, s.levels = {};
}

// try_shell over every shell, and when the set is refused, the first alone (nothing orders two
// shells' points beside each other), if it too covers more than `min_area` mm². why(area): the
// notice's reason for the shells printed, given their curved area. The plans' rasters go before
// each gate; a retry plans the first shell again (choose_shells' first is choose_shell's).
Expected<std::optional<SliceResult>> try_shells(const TriangleMesh& mesh, const SliceJob& job,
                                                const Analysis& a,
                                                std::vector<layers::ShellPlan> shells,
                                                const std::function<std::string(double)>& why,
                                                double min_area, SliceResult& planar,
                                                EarlyEngine* early, const Context& ctx) {
  auto spent = [&] {
    for (layers::ShellPlan& s : shells) drop_rasters(s);
  };
  auto printed = try_shell(mesh, job, shells, why(area_of(a, shell_patches(shells))), planar, spent,
                           early, ctx);
  if (!printed || *printed || shells.size() == 1) return printed;
  const double first = area_of(a, shells.front().patches);
  if (!(first > min_area)) return printed;
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};  // before planning again
  shells.assign(1, layers::choose_shell(mesh, a, job.layers));
  return try_shell(mesh, job, shells, why(first), planar, spent, early, ctx);
}

// Where a shell cuts the core inside a stack's band (none: nowhere). Core layer k is cut
// inside a shell's R where z_k > B + a, at the core's planar height, which a band's curved
// layers are not at. Looked at every 0.5 mm of each band's reach (1 mm of slack): material
// there above B + a and below the band's top, from its plane c up.
std::optional<Vec2> cut_in_a_band(const TriangleMesh& mesh, const layers::BandedField& field,
                                  const std::vector<layers::ShellPlan>& shells) {
  const ColumnCaster columns(mesh);
  for (std::size_t b = 0; b < field.bands().size(); ++b) {
    const layers::BandedField::Reach& reach = field.reach()[b];
    const double c = field.bands()[b].c;
    for (double x = reach.lo.x() - 1; x <= reach.hi.x() + 1; x += 0.5)
      for (double y = reach.lo.y() - 1; y <= reach.hi.y() + 1; y += 0.5)
        for (const layers::ShellPlan& s : shells) {
          const double cut = s.bottom(x, y) + s.reach;
          if (!s.in_region(x, y) || cut >= reach.z_top) continue;
          for (const auto& [lo, hi] : columns.intervals(x, y))
            if (hi > std::max(cut, c) + 1e-6 && lo < reach.z_top) return Vec2(x, y);
        }
  }
  return std::nullopt;
}

// Stacks and shells in one part (#19): the curved patches the stacks of `stacked` (sliced and
// passed) leave planar get shells, over a core that holds the stacks' curved layers. The
// shells' core has even layers (h_c after the first), and the stacks are planned again on
// them, so one field bends the core's layers under the stacks and is planar where the shells
// cut the core back. Only with the built-in engine (an engine's run cannot stop its core for
// the shells), only shells that print where the part stands nowhere above them (R), only when
// every stack plans again and no shell cuts the core inside a band. None: print `stacked`.
Expected<std::optional<SliceResult>> shells_beside_stacks(const TriangleMesh& mesh,
                                                          const SliceJob& job, const Prepared& pre,
                                                          SliceResult& stacked,
                                                          const Context& ctx) {
  const std::optional<SliceResult> none;
  const Analysis& a = pre.analysis;
  if (job.engine.engine != Engine::builtin || job.one_run_shells || stacked.plan.stacks.empty())
    return none;
  const std::vector<int> stacked_ids = stacked_patches(stacked.plan);
  std::vector<int> rest;
  std::string refused;
  const auto curved = std::count_if(a.patches.begin(), a.patches.end(),
                                    [](const Patch& q) { return q.needs_nonplanar(); });
  if (static_cast<std::size_t>(curved) > stacked_ids.size()) ctx.progress("shell", 0);
  std::vector<layers::ShellPlan> shells =
      layers::choose_shells_beside(mesh, a, job.layers, stacked_ids, rest, refused, &ctx);
  // Why not, said of the patches left planar (the run's summary gives the first reason).
  auto not_beside = [&](const std::string& why) {
    stacked.notices.push_back(
        {Notice::Kind::shell_refused, -1,
         patch_names(rest) + " not printed as a shell beside the stacks: " + why});
    return none;
  };
  if (rest.empty()) return none;
  if (shells.empty()) return not_beside(refused);
  const layers::ShellPlan& first = shells.front();
  LayerParams on_core = job.layers;
  on_core.first_layer_height = first.core[1];
  on_core.layer_height = first.core[2] - first.core[1];
  std::vector<SurfaceFit> fits;
  std::vector<int> ids;
  for (std::size_t i = 0; i < pre.ids.size(); ++i)
    if (std::find(stacked_ids.begin(), stacked_ids.end(), pre.ids[i]) != stacked_ids.end())
      fits.push_back(pre.fits[i]), ids.push_back(pre.ids[i]);
  // The stacks already print: an error on the way (but Ctrl-C) leaves them as they are.
  auto failed = [&](const Error& e) -> Expected<std::optional<SliceResult>> {
    if (e.status == Status::cancelled) return e;
    return not_beside(e.message);
  };
  auto plan = plan_layers(mesh, a, fits, ids, on_core, ctx);
  if (!plan) return failed(plan.error());
  const auto* banded = dynamic_cast<const layers::BandedField*>(plan->field.get());
  char buf[200];
  if (plan->stacks.size() != stacked_ids.size() || !banded) {
    std::snprintf(buf, sizeof buf, "a stack does not fit the core's %.2f mm layers",
                  on_core.layer_height);
    return not_beside(buf);
  }
  if (const auto at = cut_in_a_band(mesh, *banded, shells)) {
    std::snprintf(buf, sizeof buf,
                  "it would cut the core back where a stack bends its layers, near (%.2f, %.2f)",
                  at->x(), at->y());
    return not_beside(buf);
  }
  const std::string why = std::to_string(plan->stacks.size()) +
                          (plan->stacks.size() == 1 ? " curved stack" : " curved stacks") +
                          " beside it";
  auto both = try_shell(
      mesh, job, shells, why, stacked, [] {}, nullptr, ctx, &*plan);
  if (!both) return failed(both.error());
  return both;
}

}  // namespace

namespace {

// A patch the final paths dropped, planar, with what its stack knew: when its layers were
// too thin for the nozzle tip on its slopes, the limit and the value that would have let it
// clear (#16: the MK3S's 0.15 mm SPEED preset on the saddle).
Notice dropped_notice(const SliceResult& r, int patch, const std::string& why,
                      const SliceJob& job) {
  Notice n = planar_notice(patch, "in its final paths " + why);
  for (const LayerStack& st : r.plan.stacks) {
    if (st.patch != patch || st.tip_needs_max_layer_height <= 0) continue;
    const double need = st.tip_needs_max_layer_height;
    char buf[240];
    n.names_a_fix = need <= job.print.paths.nozzle_diameter;
    if (!n.names_a_fix)
      std::snprintf(buf, sizeof buf,
                    "; its slopes need layers thicker than the nozzle allows (%.2f mm)", need);
    else
      std::snprintf(buf, sizeof buf,
                    "; its slopes need thicker layers than max_layer_height = %.2f mm allows: "
                    "--max-layer-height %.2f would let the nozzle tip clear them",
                    job.layers.max_layer_height, need);
    n.text += buf;
    break;
  }
  return n;
}

// A part whose stacks follow only a little of its curved top (the CurviSlicer car: 172 mm² of
// roof, while its 486 mm² body, hollow under the hood, has none): a shell instead, if that
// plans and passes the gate: over all its curved patches (the car: 1065 mm², 84 % of its
// curved top within 0.03 mm, where the body alone gave 57 %), else over the group round the
// largest or the largest alone, and one per further curved region (layers::choose_shells).
// Stacks follow the top more closely and cost no bands, so the shell must cover more than
// twice their area (shell_may_cover_more asks it of all curved patches first; `stacked` is an
// attempt it deferred, its stacks planned but not sliced). Output: the shell's result when it
// prints; else none, with the stacks' attempt sliced in `stacks` (their offenders in
// `offenders`) and why the shell did not print in stacked.notices.
// Through another slicer the shell is planned first too: its pieces go between the engine's
// core layers where the part stands above it, so the bunny, Benchy, the ornament, the car and
// the spiky block print theirs (a run of the stacks started beside the plan, for a shell one
// run would refuse, took both cores from it: the bunny's plan 6 s, not 1).
Expected<std::optional<SliceResult>> shell_before_stacks(
    const TriangleMesh& mesh, const SliceJob& job, const Prepared& pre,
    const std::vector<int>& excluded, SliceResult& stacked,
    std::optional<Expected<SliceResult>>& stacks,
    std::vector<std::pair<int, std::string>>& offenders, const Context& ctx) {
  ctx.progress("shell", 0);
  std::vector<layers::ShellPlan> shells =
      planned(pre, ctx, [&](const Context& c) { return shells_for(mesh, pre.analysis, job, c); });
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  const double area = area_of(pre.analysis, stacked_patches(stacked.plan));
  const bool larger = area_of(pre.analysis, shell_patches(shells)) > 2 * area;
  // One run's refusal (shells_for) is said, as when the shell was planned whole and then refused.
  if (const layers::ShellPlan& first = shells.front();
      larger && !first.refused.empty() && first.refused == shell_choice(job, ctx).whole_only)
    stacked.notices.push_back(
        {Notice::Kind::shell_refused, -1,
         patch_names(first.patches) + " not printed as a shell: " + first.refused});
  if (shells.front().refused.empty() && larger) {
    auto why = [&](double curved) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "its %.0f mm² print curved, where stacks would cover %.0f mm²",
                    curved, area);
      return std::string(buf);
    };
    auto shell = try_shells(mesh, job, pre.analysis, std::move(shells), why, 2 * area, stacked,
                            pre.engine.get(), ctx);
    if (!shell || *shell) return shell;
  }
  std::vector<layers::ShellPlan>().swap(shells);  // gone before the stacks are sliced
  stacks = attempt(mesh, job, pre, excluded, &offenders, nullptr, false, ctx);
  return std::optional<SliceResult>{};
}

// slice_model's rounds: attempts, retries without the patches that broke a limit, shells.
Expected<SliceResult> slice_rounds(const TriangleMesh& mesh, const SliceJob& job,
                                   const Context& ctx) {
  Prepared pre;
  if (!job.planar_only) {
    pre.engine = start_engine_early(job.engine, job.print, mesh);
    auto a = analyze(mesh, job.analysis, ctx);
    if (!a) return a.error();
    pre.analysis = std::move(*a);
    // Where the part stands above a curved top, its shells print through PrusaSlicer in pieces
    // between the layers of one run of the part alone, on boundaries known now: that run goes
    // on while the stacks and shells are planned (on the bunny 1.3 s), and any other run
    // stops it. A mesh PrusaSlicer would repair has no engine started early for any run: one
    // starts now for this one (the CurviSlicer car's run 0.3 s sooner).
    if (job.engine.engine == Engine::prusaslicer && job.shells)  // (pre.engine: PrusaSlicer's)
      if (auto core = layers::region_shells_core(mesh, pre.analysis, job.layers)) {
        if (!pre.engine) pre.engine = start_engine_early(job.engine, job.print, mesh, true);
        EngineRun run;
        run.layer_tops.assign(core->begin() + 1, core->end());
        if (pre.engine)
          run_engine_ahead(*pre.engine, job.engine, mesh, job.print, std::move(run), ctx);
      }
    auto fits = planned(pre, ctx, [&](const Context& c) {
      return fit_for_plan(mesh, pre.analysis, job.fit, job.layers, pre.stacks, &pre.ids, c);
    });
    if (!fits) return fits.error();
    pre.fits = std::move(*fits);
  }
  int candidates = 0;
  for (const Patch& p : pre.analysis.patches) candidates += p.needs_nonplanar();
  auto done = [&](Expected<SliceResult> r) {
    if (r) r->curved_patches = candidates;
    return r;
  };
  std::vector<int> excluded;
  std::vector<Notice> dropped;
  std::vector<std::pair<int, std::string>> offenders;
  // OrcaSlicer prints no shells (its command line cannot take our layer boundaries): with it,
  // a part without stacks slices planar at once.
  const bool shells = job.shells && job.engine.engine != Engine::orcaslicer;
  bool over_stacks_tried = false;
  bool stacks_broke = false;  // the gate refused a stack: a shell then says so, not "none fits"
  for (int round = 0; round < 8; ++round) {
    bool deferred = false;
    auto r = attempt(mesh, job, pre, excluded, &offenders, shells ? &deferred : nullptr,
                     !over_stacks_tried, ctx);
    if (!r) return r;
    // Before planning shells (seconds on a large part under a sanitizer, past Ctrl-C's grace).
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    if (deferred && !r->plan.stacks.empty()) {
      over_stacks_tried = true;
      r->notices.insert(r->notices.begin(), dropped.begin(), dropped.end());
      std::optional<Expected<SliceResult>> stacks;
      auto shell = shell_before_stacks(mesh, job, pre, excluded, *r, stacks, offenders, ctx);
      if (!shell) return shell.error();
      if (*shell) return done(std::move(**shell));
      // The stacks, then; and why the shell did not print, if it got as far as the gate (kept
      // through the rounds, as the patches dropped are).
      for (const Notice& n : r->notices)
        if (n.kind == Notice::Kind::shell_refused) dropped.push_back(n);
      r = std::move(*stacks);
      if (!r) return r;
    } else if (deferred) {
      // No curved stack: a shell, or else the same attempt sliced planar (its stacks cached).
      r->notices.insert(r->notices.begin(), dropped.begin(), dropped.end());
      ctx.progress("shell", 0);
      // All the patches that need curved layers, taken as one top (the CurviSlicer airfoil's
      // top is two, split at a crease); failing that, the group round the largest, or the
      // largest alone; and a shell per further curved region the part stands above.
      auto shell = try_shells(
          mesh, job, pre.analysis, shells_for(mesh, pre.analysis, job, ctx),
          [&](double) {
            return std::string(stacks_broke ? "its stacks broke a limit in their final paths"
                                            : "no stack over a plane fits it");
          },
          0, *r, pre.engine.get(), ctx);
      if (!shell) return shell.error();
      if (*shell) return done(std::move(**shell));
      const std::vector<Notice> notices = std::move(r->notices);
      r = attempt(mesh, job, pre, excluded, &offenders, nullptr, false, ctx);
      if (!r) return r;
      r->notices = notices;
      return done(std::move(r));
    }
    if (offenders.empty()) {
      r->notices.insert(r->notices.begin(), dropped.begin(), dropped.end());
      // Not after a shell over the stacks was refused: the same refusal, as a rule, again (on
      // Benchy, the map's size: 1.1 s more for nothing).
      if (shells && r->nonplanar && !over_stacks_tried) {
        auto both = shells_beside_stacks(mesh, job, pre, *r, ctx);
        if (!both) return both.error();
        if (*both) return done(std::move(**both));
      }
      return done(std::move(r));
    }
    // A stack that met every limit on its own grid broke one in the final paths: print
    // that patch planar rather than refuse the part.
    // A patch that fell back in this attempt stays planar too. Its blend may only have
    // failed beside a band dropped now, so it could pass next time; but each such comeback
    // costs a whole attempt, and on the bunny both comebacks (patches 5 and 13) then collided.
    for (const PlanarFallback& fb : r->plan.fallbacks) {
      excluded.push_back(fb.patch);
      dropped.push_back(planar_notice(fb.patch, fb.reason));
    }
    stacks_broke = true;
    for (const auto& [patch, why] : offenders) {
      excluded.push_back(patch);
      dropped.push_back(dropped_notice(*r, patch, why, job));
    }
  }
  return Error{Status::internal_error, "safety check: still failing after dropping 8 patches"};
}

// When some curved patch printed planar, one line to end on: how many did not, and the first
// reason given (the notices before it say the rest).
std::optional<Notice> summary(const SliceResult& r) {
  if (r.curved_patches == 0 || r.printed_curved >= r.curved_patches) return std::nullopt;
  std::string why;  // a limit to change first, else the shell's refusal (the last thing
                    // tried), else a patch's own reason
  for (const bool fix : {true, false})
    for (const Notice::Kind kind : {Notice::Kind::shell_refused, Notice::Kind::patch_planar})
      for (const Notice& n : r.notices)
        if (why.empty() && n.kind == kind && n.names_a_fix == fix) why = n.text;
  if (why.size() > 320) why = why.substr(0, 317) + "...";
  std::string text = std::to_string(r.printed_curved) + " of " + std::to_string(r.curved_patches) +
                     (r.curved_patches == 1 ? " curved patch" : " curved patches") +
                     " printed curved";
  if (r.printed_curved == 0) text += ", the print is planar";
  if (!why.empty()) text += " (" + why + ")";
  return Notice{Notice::Kind::summary, -1, text};
}

}  // namespace

Expected<SliceResult> slice_model(const TriangleMesh& mesh, const SliceJob& job,
                                  const Context& ctx) {
  auto r = slice_rounds(mesh, job, ctx);
  if (!r) return r;
  if (auto s = summary(*r)) r->notices.push_back(*s);
  if (auto e = nothing_to_print(*r, mesh)) return *e;
  if (auto w = write_program(*r, job, ctx); !w) return w.error();
  // Time, progress and filament of the file as written, by either engine (an engine's own
  // were for the flattened part).
  if (!r->stats_in_gcode) {
    ctx.progress("stats", 0);
    r->gcode = with_print_stats(r->gcode, job.print, &r->stats);
  }
  r->notices.insert(r->notices.begin(), job.notices.begin(), job.notices.end());
  return r;
}

}  // namespace nonplanar
