// plan_layers: stacks per patch, then the field, then a check of the blend zones inside the
// material; a patch whose blend breaks a limit is dropped to planar and the field rebuilt.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <optional>

#include "core/column_caster.hpp"
#include "core/parallel.hpp"
#include "layers/banded_field.hpp"
#include "layers/stack_builder.hpp"

namespace nonplanar {
namespace {

using layers::Band;
using layers::BandedField;
using layers::PlanarLayers;

std::optional<Error> check(const LayerParams& p) {
  auto bad = [](const char* key, const std::string& why) {
    return Error{Status::invalid_argument, std::string(key) + ": " + why};
  };
  auto pos = [](double v) { return std::isfinite(v) && v > 0; };
  if (!pos(p.layer_height)) return bad("layer_height", "must be a finite number > 0");
  if (!pos(p.first_layer_height)) return bad("first_layer_height", "must be a finite number > 0");
  if (!pos(p.min_layer_height)) return bad("min_layer_height", "must be a finite number > 0");
  if (!pos(p.max_layer_height)) return bad("max_layer_height", "must be a finite number > 0");
  if (p.min_layer_height > p.max_layer_height)
    return bad("min_layer_height", "is greater than max_layer_height");
  if (p.layer_height < p.min_layer_height || p.layer_height > p.max_layer_height)
    return bad("layer_height", "must lie in [min_layer_height, max_layer_height]");
  if (!std::isfinite(p.max_angle_deg) || p.max_angle_deg <= 0 || p.max_angle_deg >= 90)
    return bad("max_angle", "must be in (0, 90) degrees");
  const Toolhead& h = p.toolhead;
  if (!pos(h.block_radius) || !pos(h.block_clearance) || !pos(h.tip_radius))
    return bad("heater_block_radius/heater_block_clearance/nozzle_tip_radius",
               "must be finite numbers > 0");
  if (!std::isfinite(h.cone_angle_deg) || h.cone_angle_deg <= 0 || h.cone_angle_deg >= 90)
    return bad("nozzle_cone_angle", "must be in (0, 90) degrees");
  if (!(h.clearance() > 0) || !std::isfinite(h.reach()))
    return bad("toolhead_shape", "its lowest slice must be above the nozzle tip");
  if (!std::isfinite(p.continuity_weight) || p.continuity_weight < 0)
    return bad("continuity_weight", "must be >= 0");
  if (!pos(p.grid_step)) return bad("grid_step", "must be > 0");
  if (p.max_iterations < 0) return bad("max_iterations", "must be >= 0");
  return std::nullopt;
}

// Whether band `a`'s β may be non-zero at a column check_blend looks at for band `b` (the
// nodes of b's blend raster). Band::beta is 0 two cells and more before a's raster and one
// cell and more past its last node; a cell more either way for rounding.
bool reaches(const Band& a, const Band& b) {
  const Vec2 a_lo = a.blend_origin - Vec2(3, 3) * a.blend_cell;
  const Vec2 a_hi = a.blend_origin + Vec2(a.blend_nx + 2, a.blend_ny + 2) * a.blend_cell;
  const Vec2 b_lo = b.blend_origin;
  const Vec2 b_hi = b.blend_origin + Vec2(b.blend_nx, b.blend_ny) * b.blend_cell;
  return a_lo.x() <= b_hi.x() && b_lo.x() <= a_hi.x() && a_lo.y() <= b_hi.y() &&
         b_lo.y() <= a_hi.y();
}

// check_blend's columns: every stride-th node (i, j) of b's blend raster where 0 < β < 1, in
// order, found a row at a time side by side; *top_max the highest S_0 among them.
std::vector<std::pair<int, int>> blend_columns(const Band& b, int stride, double* top_max) {
  const int rows = (b.blend_nx + stride - 1) / stride;
  std::vector<std::vector<int>> row_cols(static_cast<std::size_t>(rows));
  std::vector<double> row_top(static_cast<std::size_t>(rows), -1e300);
  core::parallel_for(0, rows, [&](int r) {
    const int i = r * stride;
    for (int j = 0; j < b.blend_ny; j += stride) {
      const double x = b.blend_origin.x() + i * b.blend_cell,
                   y = b.blend_origin.y() + j * b.blend_cell;
      const double beta = b.beta(x, y);
      if (beta <= 0 || beta >= 1) continue;
      row_top[r] = std::max(row_top[r], b.surface(b.basis(x, y), 0));
      row_cols[r].push_back(j);
    }
  });
  std::vector<std::pair<int, int>> cols;
  for (int r = 0; r < rows; ++r) {
    *top_max = std::max(*top_max, row_top[r]);
    for (const int j : row_cols[r]) cols.emplace_back(r * stride, j);
  }
  return cols;
}

// Layers through the blend zone of band `b` (0 < β < 1) where there is material: thickness
// and slope. Returns a reason, or empty. Columns every 0.5 mm: at 1 mm a thin part (the
// bunny's ear) left few neighbouring columns both in material, and a 30.3° blend there was
// found only in the final paths, after a whole slice (through PrusaSlicer, a run more).
std::string check_blend(const BandedField& field, const Band& b, const ColumnCaster& columns,
                        const LayerParams& p) {
  const double step = 0.5;
  const int stride = std::max(1, static_cast<int>(step / b.blend_cell));
  double top_max = -1e300;
  const std::vector<std::pair<int, int>> cols = blend_columns(b, stride, &top_max);
  std::map<std::pair<int, int>, std::vector<double>> zk;  // layer boundary heights per column
  const double T0 = b.T_bottom;
  if (cols.empty()) return {};
  const int k_hi = static_cast<int>(std::ceil(field.t_of_zeta(top_max + b.fade))) + 1;
  // Layer boundaries per column (root-finding: the cost of this check), in parallel; the
  // verdicts below walk the columns in order, so the reported place does not depend on it.
  std::vector<double> ks;
  for (int k = static_cast<int>(T0); k <= k_hi; ++k) ks.push_back(k);
  std::vector<std::vector<double>> zc(cols.size());
  std::vector<std::vector<std::pair<double, double>>> ivc(cols.size());
  core::parallel_for(std::size_t{0}, cols.size(), [&](std::size_t c) {
    const double x = b.blend_origin.x() + cols[c].first * b.blend_cell,
                 y = b.blend_origin.y() + cols[c].second * b.blend_cell;
    ivc[c] = columns.intervals(x, y);
    if (ivc[c].empty()) return;
    // All of the column's boundaries at once (its bands' bases evaluated once, each root
    // bracketed from the one below it), to 1e-7 mm: the limits are checked to 1e-4 mm.
    zc[c].resize(ks.size());
    field.z_column(x, y, ks.data(), zc[c].data(), static_cast<int>(ks.size()), 1e-7);
  });
  for (std::size_t c = 0; c < cols.size(); ++c) {
    const auto [i, j] = cols[c];
    const double x = b.blend_origin.x() + i * b.blend_cell,
                 y = b.blend_origin.y() + j * b.blend_cell;
    const auto& iv = ivc[c];
    if (iv.empty()) continue;
    std::vector<double>& z = zc[c];
    for (std::size_t k = 0; k + 1 < z.size(); ++k) {
      const double mid = 0.5 * (z[k] + z[k + 1]);
      bool in = false;
      for (const auto& [lo, hi] : iv) in |= mid > lo && mid < hi;
      if (!in) continue;
      const double t = z[k + 1] - z[k];
      if (t < p.min_layer_height - 1e-4 || t > p.max_layer_height + 1e-4) {
        char buf[200];
        std::snprintf(buf, sizeof buf,
                      "blending into the planar layers makes a %.3f mm layer at x = %.2f, y = %.2f",
                      t, x, y);
        return buf;
      }
    }
    zk[{i, j}] = std::move(z);
  }
  // Slopes between neighbouring columns that both have material at that layer.
  const double tmax = std::tan(p.max_angle_deg * M_PI / 180.0);
  for (const auto& [ij, z] : zk) {
    for (const auto& nb :
         {std::pair{ij.first + stride, ij.second}, std::pair{ij.first, ij.second + stride}}) {
      const auto it = zk.find(nb);
      if (it == zk.end()) continue;
      const double d = stride * b.blend_cell;
      for (std::size_t k = 0; k < std::min(z.size(), it->second.size()); ++k)
        if (std::abs(it->second[k] - z[k]) / d > tmax) {
          const double x = b.blend_origin.x() + ij.first * b.blend_cell;
          char buf[200];
          std::snprintf(buf, sizeof buf,
                        "blending into the planar layers tilts a layer to %.1f deg near x = %.2f",
                        std::atan(std::abs(it->second[k] - z[k]) / d) * 180 / M_PI, x);
          return buf;
        }
    }
  }
  return {};
}

}  // namespace

std::shared_ptr<const LayerField> planar_field(const LayerParams& p) {
  return std::make_shared<BandedField>(PlanarLayers{p.first_layer_height, p.layer_height},
                                       std::vector<Band>{});
}

struct StackCache::Impl {
  std::map<int, layers::StackResult> built;  ///< by patch
  /// By patch: checks passed on the facets, the rest to build with the fit (fit_for_plan).
  std::map<int, layers::StackStart> started;
};
StackCache::StackCache() : impl_(std::make_unique<Impl>()) {}
StackCache::~StackCache() = default;

Expected<LayerPlan> plan_layers(const TriangleMesh& mesh, const Analysis& analysis,
                                const std::vector<SurfaceFit>& fits,
                                const std::vector<int>& patch_of_fit, const LayerParams& params,
                                const Context& ctx) {
  StackCache cache;
  return plan_layers(mesh, analysis, fits, patch_of_fit, params, cache, ctx);
}

namespace {

// fit_for_plan's second step: the patches fitted by least squares (`fits`, in the order of
// `ids` less the refused) refitted with `fit` in full where the facets did not decide or the
// optimiser would move the stack. Tests each start's gradient side by side (its optimiser's
// grid, kept for finish_stack, is the one member they write while prepare_blend fills others).
std::optional<Error> refine_moving(const TriangleMesh& mesh, const Analysis& analysis,
                                   const FitParams& fit, const LayerParams& params,
                                   const std::vector<int>& ids,
                                   std::vector<layers::StackStart>& early,
                                   std::vector<SurfaceFit>& fits, const Context& ctx) {
  std::vector<std::size_t> fit_of(ids.size(), SIZE_MAX);
  for (std::size_t k = 0, f = 0; k < ids.size(); ++k)
    if (early[k].result.needs_fit) fit_of[k] = f++;
  std::vector<char> refine(ids.size(), 0);
  core::parallel_for(std::size_t{0}, ids.size(), [&](std::size_t k) {
    if (fit_of[k] == SIZE_MAX || ctx.cancelled()) return;
    refine[k] = !early[k].passed || !layers::stays_even(early[k], fits[fit_of[k]].surface, params);
  });
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (!refine[k]) continue;
    if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
    auto f = fit_patch(mesh, analysis.patches[static_cast<std::size_t>(ids[k])], fit, ctx);
    if (!f) return f.error();
    fits[fit_of[k]] = std::move(*f);
  }
  return std::nullopt;
}

}  // namespace

Expected<std::vector<SurfaceFit>> fit_for_plan(const TriangleMesh& mesh, const Analysis& analysis,
                                               const FitParams& fit, const LayerParams& params,
                                               StackCache& cache, std::vector<int>* patch_of_fit,
                                               const Context& ctx) {
  if (auto e = check(params)) return *e;
  std::vector<int> ids;
  for (std::size_t i = 0; i < analysis.patches.size(); ++i)
    if (analysis.patches[i].needs_nonplanar()) ids.push_back(static_cast<int>(i));
  // Each patch's checks on its own, side by side (as plan_layers builds stacks).
  const PlanarLayers planar{params.first_layer_height, params.layer_height};
  const ColumnCaster columns(mesh);
  std::vector<layers::StackStart> early(ids.size());
  std::vector<SurfaceFit> out(ids.size());
  auto patch_of = [&](std::size_t k) -> const Patch& {
    return analysis.patches[static_cast<std::size_t>(ids[k])];
  };
  core::parallel_for(std::size_t{0}, ids.size(), [&](std::size_t k) {
    if (ctx.cancelled()) return;
    out[k].surface = fit_rectangle(patch_of(k).xy_min, patch_of(k).xy_max, fit.margin);
    early[k] =
        layers::start_stack(mesh, patch_of(k), ids[k], out[k].surface, columns, params, planar);
  });
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  std::vector<int> refused;
  for (std::size_t k = 0; k < ids.size(); ++k)
    if (!early[k].result.needs_fit) refused.push_back(ids[k]);
  // The blend's rasters of the stacks that passed, built beside the fits (they read the
  // facets only): on FoilCutter 27 ms that the stack otherwise waited for after its fit.
  core::Background beside;
  beside.run([&] {
    core::parallel_for(std::size_t{0}, ids.size(), [&](std::size_t k) {
      if (early[k].passed && !ctx.cancelled())
        layers::prepare_blend(early[k], mesh, patch_of(k), params);
    });
  });
  // With a faceted top, a stack the optimiser leaves even is c + (1 − i/N)(H − c) whatever
  // the fit (stays_even): the least-squares fit first, and the rational and nonlinear
  // refinement (FoilCutter's Levenberg–Marquardt: 45 of its 70 ms) only for the patches whose
  // stack it would move, or which the facets did not decide.
  const bool lazy =
      params.faceted_top &&
      (fit.free_weights || (fit.nonlinear != NonlinearSolver::none && fit.max_iterations > 0));
  FitParams linear = fit;
  if (lazy) linear.free_weights = false, linear.nonlinear = NonlinearSolver::none;
  std::vector<int> fitted_ids;
  auto fits = fit_patches(mesh, analysis, linear, refused, &fitted_ids, ctx);
  std::optional<Error> refined;
  if (fits && lazy) refined = refine_moving(mesh, analysis, fit, params, ids, early, *fits, ctx);
  beside.wait();
  if (!fits) return fits.error();
  if (refined) return *refined;
  // All the patches in order, the rectangle unfitted for each refused one.
  for (std::size_t k = 0, f = 0; k < ids.size(); ++k) {
    if (early[k].result.needs_fit) out[k] = std::move((*fits)[f++]);
    if (early[k].passed)
      cache.impl().started.emplace(ids[k], std::move(early[k]));
    else if (!early[k].result.needs_fit)
      cache.impl().built.emplace(ids[k], std::move(early[k].result));
  }
  *patch_of_fit = std::move(ids);
  return out;
}

Expected<LayerPlan> plan_layers(const TriangleMesh& mesh, const Analysis& analysis,
                                const std::vector<SurfaceFit>& fits,
                                const std::vector<int>& patch_of_fit, const LayerParams& params,
                                StackCache& cache, const Context& ctx) {
  ctx.progress("layers", 0);
  if (auto e = check(params)) return *e;
  if (fits.size() != patch_of_fit.size())
    return Error{Status::invalid_argument, "plan_layers: one patch index per fit expected"};
  const PlanarLayers planar{params.first_layer_height, params.layer_height};
  const ColumnCaster columns(mesh);
  for (const int pid : patch_of_fit)
    if (pid < 0 || pid >= static_cast<int>(analysis.patches.size()))
      return Error{Status::invalid_argument, "plan_layers: patch index out of range"};
  // The stacks not built yet, built side by side: each depends only on its own patch and
  // surface, so the plan does not depend on the thread count (the bunny's 25 took 2.0 s one
  // after another). A stack whose optimiser was stopped is not the plan's (nor the cache's).
  auto& built = cache.impl().built;
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < fits.size(); ++i)
    if (!built.count(patch_of_fit[i])) missing.push_back(i);
  // A stack whose checks fit_for_plan made goes on from them (with the fit of the rectangle
  // they read).
  auto& started = cache.impl().started;
  std::vector<layers::StackStart*> resume(missing.size(), nullptr);
  for (std::size_t k = 0; k < missing.size(); ++k) {
    const std::size_t i = missing[k];
    const auto it = started.find(patch_of_fit[i]);
    if (it != started.end() && !it->second.fitted && it->second.origin == fits[i].surface.origin &&
        it->second.extent == fits[i].surface.extent)
      resume[k] = &it->second;
  }
  std::vector<layers::StackResult> fresh(missing.size());
  core::parallel_for(std::size_t{0}, missing.size(), [&](std::size_t k) {
    if (ctx.cancelled()) return;
    const std::size_t i = missing[k];
    const int pid = patch_of_fit[i];
    const Patch& patch = analysis.patches[static_cast<std::size_t>(pid)];
    fresh[k] = resume[k] ? layers::finish_stack(std::move(*resume[k]), mesh, patch, fits[i].surface,
                                                params, 1.0, ctx)
                         : layers::build_stack(mesh, patch, pid, fits[i].surface, columns, params,
                                               planar, 1.0, ctx);
  });
  for (std::size_t k = 0; k < missing.size(); ++k) started.erase(patch_of_fit[missing[k]]);
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  for (std::size_t k = 0; k < missing.size(); ++k) {
    if (fresh[k].needs_fit)
      return Error{Status::invalid_argument, "plan_layers: patch " +
                                                 std::to_string(patch_of_fit[missing[k]]) +
                                                 " needs its fitted surface"};
    built.emplace(patch_of_fit[missing[k]], std::move(fresh[k]));
  }
  ctx.progress("layers", 0.8);
  LayerPlan plan;
  std::vector<Band> bands;
  for (const int pid : patch_of_fit) {
    layers::StackResult r = built.at(pid);
    if (!r.failure.empty()) {
      plan.fallbacks.push_back({pid, r.failure});
    } else {
      plan.stacks.push_back(std::move(r.stack));
      bands.push_back(std::move(r.band));
    }
  }
  // Check each blend zone in the field of all bands; drop offenders until none is left. A
  // band that passed keeps its verdict while no band dropped reaches its blend zone: where a
  // band's β is 0 the field's sums do not change without it (up to the field's 64 bands).
  // On the bunny the same passing bands were checked again after each of 5 drops (0.7 s).
  // The field is built over the bands once and again only when one is dropped: a copy of every
  // band (its rasters up to 16 MB each on the bunny) was made for each check and for the plan.
  std::vector<char> passed(bands.size(), 0);
  auto field = std::make_shared<BandedField>(planar, std::move(bands));
  for (bool changed = true; changed;) {
    changed = false;
    const std::vector<Band>& all = field->bands();
    for (std::size_t b = 0; b < all.size(); ++b) {
      if (passed[b]) continue;
      const std::string why = check_blend(*field, all[b], columns, params);
      if (why.empty()) {
        passed[b] = all.size() <= 64;
        continue;
      }
      plan.fallbacks.push_back({plan.stacks[b].patch, why});
      for (std::size_t o = 0; o < all.size(); ++o)
        if (passed[o] && reaches(all[b], all[o])) passed[o] = 0;
      std::vector<Band> kept = field->take_bands();
      kept.erase(kept.begin() + static_cast<long>(b));
      plan.stacks.erase(plan.stacks.begin() + static_cast<long>(b));
      passed.erase(passed.begin() + static_cast<long>(b));
      field = std::make_shared<BandedField>(planar, std::move(kept));
      changed = true;
      break;
    }
  }
  plan.field = std::move(field);
  ctx.progress("layers", 1.0);
  return plan;
}

}  // namespace nonplanar
