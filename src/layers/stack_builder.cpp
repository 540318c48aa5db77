#include "layers/stack_builder.hpp"
#include "core/parallel.hpp"

#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "layers/printability_cost.hpp"
#include "nurbs/solver_callbacks.hpp"

namespace nonplanar::layers {
namespace {

constexpr double kDeg = M_PI / 180.0;

std::string fmt2(const char* f, double a, double b) {
  char buf[160];
  std::snprintf(buf, sizeof buf, f, a, b);
  return buf;
}

using core::Background;  // a task run beside the caller, waited for on every way out

class StackObjective final : public ceres::FirstOrderFunction {
 public:
  /// *first: the cost at the first point evaluated (the start: ceres begins there).
  StackObjective(const StackGrid& g, const Eigen::MatrixXd& Z, const CostTerms& c,
                 std::optional<double>* first)
      : g_(g), Z_(Z), c_(c), first_(first) {}
  int NumParameters() const override { return static_cast<int>((Z_.rows() - 2) * Z_.cols()); }
  bool Evaluate(const double* x, double* cost, double* gradient) const override {
    Eigen::MatrixXd Z = Z_;
    const int n = static_cast<int>(Z.cols());
    for (int i = 1; i + 1 < Z.rows(); ++i)
      for (int j = 0; j < n; ++j) Z(i, j) = x[(i - 1) * n + j];
    Eigen::MatrixXd grad;
    *cost = printability_cost(g_, Z, c_, gradient ? &grad : nullptr);
    if (first_ && !*first_) *first_ = *cost;
    if (gradient)
      for (int i = 0; i < grad.rows(); ++i)
        for (int j = 0; j < n; ++j) gradient[i * n + j] = grad(i, j);
    return std::isfinite(*cost);
  }

 private:
  const StackGrid& g_;
  const Eigen::MatrixXd& Z_;
  CostTerms c_;
  std::optional<double>* first_;
};

constexpr double kNoLimit = 1e300;

struct Figures {
  double t_min = 1e300, t_max = -1e300, slope = 0;
  // The pair of points of one layer that comes nearest the head (or goes furthest into it):
  // how far q rises above p, what the head allows there, and the difference.
  double rise = 0, rise_allow = kNoLimit, excess = -kNoLimit;
};

// Thickness and slope over the patch's samples; rise of each layer within the block radius
// on a grid of about 1 mm. H, dH: the faceted top and its gradient at the samples (empty:
// the top is the fit), with the layers between it and the plane c in the control heights'
// proportions, as Band::surface places them.
Figures measure(const StackGrid& g, const Eigen::MatrixXd& Z, const LayerParams& p,
                const std::vector<double>& H, const std::vector<Vec2>& dH, double c) {
  Figures f;
  const int L = static_cast<int>(Z.rows());
  const int n = static_cast<int>(g.xy.size());
  std::vector<std::vector<double>> S(L, std::vector<double>(n));
  for (int k = 0; k < n; ++k) {
    double s0 = 0, s0x = 0, s0y = 0;
    for (int i = 0; i < L; ++i) {
      double s = 0, sx = 0, sy = 0;
      for (int a = 0; a < g.m; ++a) {
        const double z = Z(i, g.control(k, a));
        s += g.R[k * g.m + a] * z, sx += g.Rx[k * g.m + a] * z, sy += g.Ry[k * g.m + a] * z;
      }
      if (i == 0) s0 = s, s0x = sx, s0y = sy;
      if (!H.empty() && i + 1 < L) {
        const double d = H[k] - c, d0 = s0 - c;
        if (d0 < 0.5 * d) {  // even split
          const double w = static_cast<double>(L - 1 - i) / (L - 1);
          s = c + d * w, sx = dH[k].x() * w, sy = dH[k].y() * w;
        } else {  // S_i = c + (s − c)·q, q = (H − c)/(s_0 − c)
          const double q = d / d0;
          const double qx = (dH[k].x() * d0 - d * s0x) / (d0 * d0);
          const double qy = (dH[k].y() * d0 - d * s0y) / (d0 * d0);
          sx = sx * q + (s - c) * qx, sy = sy * q + (s - c) * qy, s = c + (s - c) * q;
        }
      }
      S[i][k] = s;
      if (g.on_patch[k]) f.slope = std::max(f.slope, std::atan(std::hypot(sx, sy)) / kDeg);
    }
    if (!g.on_patch[k]) continue;
    for (int i = 0; i + 1 < L; ++i) {
      f.t_min = std::min(f.t_min, S[i][k] - S[i + 1][k]);
      f.t_max = std::max(f.t_max, S[i][k] - S[i + 1][k]);
    }
  }
  // Rise under the head, on a 2D subgrid of about 1 mm: for each patch point p, how far a
  // point q of the same layer within the head's reach rises above what the head allows there
  // (its block allowance at q − p; the cone is the slope limit's). Offsets are sorted by
  // allowance, so the search stops at the first that layer's highest point cannot exceed.
  const int sx = std::max(1, static_cast<int>(std::lround(1.0 / g.step_x)));
  const int sy = std::max(1, static_cast<int>(std::lround(1.0 / g.step_y)));
  // Layers rise no more than the stack's own height: parts of the head above it can't touch.
  double s_lo = 1e300, s_hi = -1e300;
  for (int i = 0; i < L; ++i)
    for (int k = 0; k < n; ++k)
      if (g.on_patch[k]) s_lo = std::min(s_lo, S[i][k]), s_hi = std::max(s_hi, S[i][k]);
  const HeadClearance head(p.toolhead, s_hi - s_lo);
  struct Offset {
    int di, dj;
    double allow;
  };
  std::vector<Offset> disk;
  const double R = head.reach();
  const int rx = static_cast<int>(R / (sx * g.step_x));
  const int ry = static_cast<int>(R / (sy * g.step_y));
  for (int di = -rx; di <= rx; ++di)
    for (int dj = -ry; dj <= ry; ++dj) {
      const Vec2 d(di * sx * g.step_x, dj * sy * g.step_y);
      const double a = d.norm() <= R ? head.block_allowance(d) : kNoLimit;
      if (a < kNoLimit) disk.push_back({di * sx, dj * sy, a});
    }
  std::stable_sort(disk.begin(), disk.end(),
                   [](const Offset& u, const Offset& v) { return u.allow < v.allow; });
  f.excess = -1e300;
  for (int i = 0; i < L; ++i) {
    double top = -1e300;
    for (int k = 0; k < n; ++k)
      if (g.on_patch[k]) top = std::max(top, S[i][k]);
    for (int a = 0; a < g.nx; a += sx)
      for (int b = 0; b < g.ny; b += sy) {
        const int k = a * g.ny + b;
        if (!g.on_patch[k]) continue;
        for (const Offset& o : disk) {
          if (top - S[i][k] - o.allow <= f.excess) break;
          const int a2 = a + o.di, b2 = b + o.dj;
          if (a2 < 0 || b2 < 0 || a2 >= g.nx || b2 >= g.ny) continue;
          const int k2 = a2 * g.ny + b2;
          if (!g.on_patch[k2]) continue;
          const double rise = S[i][k2] - S[i][k];
          if (rise - o.allow > f.excess)
            f.excess = rise - o.allow, f.rise = rise, f.rise_allow = o.allow;
        }
      }
  }
  return f;
}

}  // namespace

StackStart start_stack(const TriangleMesh& mesh, const Patch& patch, int patch_id,
                       const HeightField& top, const ColumnCaster& columns, const LayerParams& p,
                       const PlanarLayers& planar) {
  StackStart s;
  StackResult& out = s.result;
  // Without a fitted surface, only the checks the facets decide (build_stack's header).
  const bool fitted = !top.surface.points.empty();
  if (!fitted && !p.faceted_top) return out.needs_fit = true, s;
  LayerStack& st = out.stack;
  st.patch = patch_id;
  st.xy_min = patch.xy_min;
  st.xy_max = patch.xy_max;
  s.raster = rasterize_patch(mesh, patch, std::max(0.1, p.grid_step / 2), 0.0);
  const PatchRaster& raster = s.raster;
  // Figures on a fine grid (the optimiser's quadrature is finish_stack's).
  StackGrid& grid = s.grid;
  s.fitted = fitted, s.origin = top.origin, s.extent = top.extent;
  s.step = std::max(p.grid_step, std::max(top.extent.x(), top.extent.y()) / 100.0);
  build_stack_grid(grid, top, s.step, raster.mask, raster.origin, raster.cell, raster.nx,
                   raster.ny);

  // Heights of the top over the whole rectangle (the stack must be valid where it blends).
  // It follows the facets (the band's raster, built last, carries them past the rim).
  const int n = static_cast<int>(grid.xy.size());
  std::vector<double> top_z(n), top_tan(n, 0.0);
  std::vector<double>& H = s.H;
  std::vector<Vec2>& dH = s.dH;
  FacetSamples fs;
  if (p.faceted_top) {
    fs = facet_samples(mesh, patch, grid.xy, grid.on_patch);
    H.resize(n), dH.resize(n);
    for (int k = 0; k < n; ++k) {
      const bool ok = std::isfinite(fs.h[k]) && fs.slope[k].allFinite();
      if (!ok && !fitted && grid.on_patch[k]) return out.needs_fit = true, s;
      // Off the patch: read after the checks below only (finish_stack, from the fit).
      if (!ok && !fitted) {
        s.off_facets.push_back(k);
        continue;
      }
      H[k] = ok ? fs.h[k] : top.height(grid.xy[k].x(), grid.xy[k].y());
      dH[k] = ok ? fs.slope[k] : top.gradient(grid.xy[k].x(), grid.xy[k].y());
    }
  }
  double zmin = 1e300, zmax = -1e300, on_sum = 0, top_slope = 0;
  int on_count = 0;
  for (int k = 0; k < n; ++k) {
    top_z[k] = H.empty() ? top.height(grid.xy[k].x(), grid.xy[k].y()) : H[k];
    // Relief over the patch itself: off it, the fit is held only by its smoothness term and
    // may swing (the blend check below judges the layers there, in the material).
    if (grid.on_patch[k]) {
      zmin = std::min(zmin, top_z[k]);
      zmax = std::max(zmax, top_z[k]);
    }
    if (grid.on_patch[k]) {
      on_sum += top_z[k], ++on_count;
      const Vec2 g = H.empty() ? top.gradient(grid.xy[k].x(), grid.xy[k].y()) : dH[k];
      top_tan[k] = g.norm();
      top_slope = std::max(top_slope, std::atan(top_tan[k]) / kDeg);
    }
  }
  // The facets' own range (grid samples can miss a low vertex at the rim).
  if (p.faceted_top) zmin = std::min(zmin, fs.h_lo), zmax = std::max(zmax, fs.h_hi);
  if (on_count == 0) {
    out.failure = "patch covers no sample of its grid";
    return s;
  }
  if (top_slope > p.max_angle_deg) {
    out.failure =
        fmt2("surface slope %.1f deg exceeds max_angle %.1f deg", top_slope, p.max_angle_deg);
    return s;
  }
  // c: deep enough that (relief + d) / d ≤ h_max / h_min, on a planar boundary.
  const double relief = zmax - zmin;
  const double ratio = p.max_layer_height / p.min_layer_height;
  const double d_req = std::max(relief / (ratio - 1.0) * 1.15, 2 * p.min_layer_height);
  const double c_max = zmin - d_req;
  const double k = std::floor((c_max - p.first_layer_height) / p.layer_height + 1e-9);
  if (k < 0) {
    // One plane under the whole patch must sit relief / (h_max/h_min − 1) below its lowest
    // point and above the first layer.
    out.failure = fmt2(
        "relief %.2f mm needs the stack's plane %.2f mm below the surface's lowest "
        "point, which is below the first layer",
        relief, d_req);
    return s;
  }
  // N for a plane c: about h thick on average, within the thickness limits with a margin.
  const double mean_top = on_sum / on_count;
  const auto count_for = [&](double c, bool fewest) {
    const int lo = static_cast<int>(std::ceil((zmax - c) / (0.97 * p.max_layer_height)));
    const int hi = static_cast<int>(std::floor((zmin - c) / (1.03 * p.min_layer_height)));
    const int N = fewest ? lo : static_cast<int>(std::lround((mean_top - c) / p.layer_height));
    return std::min(std::max(N, lo), hi);
  };
  // The nozzle tip's flat reaches over the earlier layer uphill: at slope θ, a layer thinner
  // than r·tan θ − h/2 fires DESIGN.md §3's collision test (the sphere's rim: 29.7° and
  // 0.11 mm), and the test's 0.2 mm cells reach a little farther; 0.1 mm more than r keeps
  // the sphere clear (0.05 did not, and left `check` reading 0.08 mm layers on FoilCutter).
  // With the even stack a layer is (S_0 − c)/N thick and no steeper than the top, so take
  // the highest plane c, and there the most layers, that keep every patch sample clear; when
  // none does, keep the first choice for the gate to judge.
  // The thinnest layer the tip clears at sample kk.
  const auto need = [&](int kk) {
    return (p.toolhead.tip_radius + 0.1) * top_tan[kk] - 0.5 * p.layer_height;
  };
  // The most layers over plane c that clear the tip everywhere (0: none), without h_max.
  const auto most_clear = [&](double c) {
    double n_max = 1e9;
    for (int kk = 0; kk < n; ++kk)
      if (grid.on_patch[kk] && need(kk) > 0) n_max = std::min(n_max, (top_z[kk] - c) / need(kk));
    return static_cast<int>(std::max(n_max, -1.0));
  };
  const auto tip_clear = [&](double c, int N) { return N >= 1 && N <= most_clear(c); };
  double k_pick = k, hint = 1e300;
  int N = count_for(p.first_layer_height + k * p.layer_height, false);
  for (double kk = k; kk >= 0 && kk > k - 200; --kk) {
    const double c = p.first_layer_height + kk * p.layer_height;
    const int a = count_for(c, false), b = count_for(c, true);
    const int clear = tip_clear(c, a) ? a : tip_clear(c, b) ? b : 0;
    if (clear > 0) {
      k_pick = kk, N = clear, hint = 1e300;
      break;
    }
    // What h_max would let this plane's clear stack be (count_for keeps 3 % margin).
    if (const int m = most_clear(c); m >= 1) hint = std::min(hint, (zmax - c) / m / 0.97);
  }
  if (hint < 1e299) st.tip_needs_max_layer_height = std::ceil(hint * 100 - 1e-6) / 100;
  st.c = p.first_layer_height + k_pick * p.layer_height;
  st.T_bottom = planar.T(st.c);
  const double D_min = zmin - st.c, D_max = zmax - st.c;
  if (N < 1 || D_max / N > p.max_layer_height || D_min / N < p.min_layer_height || N > 500) {
    out.failure = fmt2(
        "relief %.2f mm cannot be split into layers within the thickness limits "
        "(%.2f mm below the patch)",
        relief, D_min);
    return s;
  }
  st.layers = N;
  // Material: solid from c up to the top under the patch, nothing just above it. Each
  // sample's columns side by side; the first offender in order is the one reported.
  enum : char { kFine, kNotSolid, kAbove };
  std::vector<char> material(static_cast<std::size_t>(n), kFine);
  core::parallel_for(0, n, [&](int kk) {
    if (!grid.on_patch[kk]) return;
    const double x = grid.xy[kk].x(), y = grid.xy[kk].y();
    bool meets_top = false, solid = false, above = false;
    for (const auto& [lo, hi] : columns.intervals(x, y)) {
      // The interval whose top is the patch (the fit is within a fraction of a mm).
      if (hi >= top_z[kk] - 0.05 && hi <= top_z[kk] + 0.05) {
        meets_top = true;
        solid = lo <= st.c + 1e-6;
      }
      // Material above within reach of the band's fade would be sliced by bent layers.
      if (lo > top_z[kk] + 0.05 && lo < top_z[kk] + 4.5 * (relief + p.layer_height) + 2.0)
        above = true;
    }
    if (!meets_top) return;  // a sample at the patch's rim, just off the part
    material[static_cast<std::size_t>(kk)] = !solid ? kNotSolid : above ? kAbove : kFine;
  });
  for (int kk = 0; kk < n; ++kk) {
    const char m = material[static_cast<std::size_t>(kk)];
    const double x = grid.xy[kk].x(), y = grid.xy[kk].y();
    if (m == kNotSolid) {
      out.failure = fmt2("part is not solid from z = %.2f up to the patch at x = %.2f", st.c, x);
      return s;
    }
    if (m == kAbove) {
      out.failure =
          fmt2("other material of the part lies above the patch at x = %.2f, y = %.2f", x, y);
      return s;
    }
  }
  // How far the curved layers sit from the planar ones decides how gently they blend.
  double dev = 0;
  for (int kk = 0; kk < n; ++kk)
    if (grid.on_patch[kk]) dev = std::max(dev, std::abs(top_z[kk] - (st.c + N * p.layer_height)));
  s.fade = std::max(1.0, 4.5 * dev);
  s.blend = std::max(2.0, 1.3 * 1.5 * dev / std::tan(p.max_angle_deg * kDeg));
  s.zmin = zmin, s.zmax = zmax;
  s.passed = true;
  out.needs_fit = !fitted;
  return s;
}

void prepare_blend(StackStart& s, const TriangleMesh& mesh, const Patch& patch,
                   const LayerParams& p) {
  // The two rasters side by side (each reads the facets only): the caller's fit may be done
  // first and take one (on the sine roof the faceted top took 9 ms, the wide raster 1).
  const double wide_cell = std::max(0.25, p.grid_step / 2);
  core::Background beside;
  // β reaches two of its cells past its raster. Off the patch the top may bend no steeper
  // than 0.8 max_angle along the raster's axes, so its bilinear interpolation (whose
  // gradient can be √2 times that) stays printable: on the bunny a single-facet patch's
  // continuation made a 31° path 1 mm past its corner.
  if (p.faceted_top)
    beside.run([&] {
      s.band_facets = faceted_top(mesh, patch, 0.1, s.blend + 2.0 + 3 * wide_cell,
                                  std::tan(0.8 * p.max_angle_deg * kDeg) / M_SQRT2);
    });
  s.wide = rasterize_patch(mesh, patch, wide_cell, s.blend + 2.0);
  beside.wait();
  s.blend_ready = true;
}

namespace {

bool same_top(const HeightField& a, const HeightField& b) {
  const NurbsSurface &u = a.surface, &v = b.surface;
  return a.origin == b.origin && a.extent == b.extent && u.p == v.p && u.q == v.q && u.U == v.U &&
         u.V == v.V && u.points == v.points && u.weights == v.weights;
}

// The optimiser's quadrature on a grid of about 40 × 40 points, but at least two samples per
// knot span, or the layers could wiggle between samples; with the cost's round stand-in for
// the head, its lowest part over the block's disk (the rise check uses the whole shape).
std::shared_ptr<const StackStart::Coarse> coarse_grid(const StackStart& s, const HeightField& top,
                                                      const LayerParams& p) {
  auto c = std::make_shared<StackStart::Coarse>();
  c->on = top;
  double span = 1e300;
  for (std::size_t i = 0; i + 1 < top.surface.U.size(); ++i)
    if (top.surface.U[i + 1] > top.surface.U[i])
      span = std::min(span, (top.surface.U[i + 1] - top.surface.U[i]) * top.extent.x());
  for (std::size_t i = 0; i + 1 < top.surface.V.size(); ++i)
    if (top.surface.V[i + 1] > top.surface.V[i])
      span = std::min(span, (top.surface.V[i + 1] - top.surface.V[i]) * top.extent.y());
  const double step =
      std::max(s.step, std::min(std::max(top.extent.x(), top.extent.y()) / 40.0, span / 2.0));
  const PatchRaster& r = s.raster;
  build_stack_grid(c->grid, top, step, r.mask, r.origin, r.cell, r.nx, r.ny);
  c->grid.pair_within(std::min(p.toolhead.block_radius, p.toolhead.reach()), 2.0);
  return c;
}

// S_i = (1 − a_i) S_f + a_i c, a_i = (i/N)^power, as control heights (layers × controls).
Eigen::MatrixXd starting_stack(const HeightField& top, int N, double c, double power) {
  const int nc = top.surface.n_u * top.surface.n_v;
  Eigen::MatrixXd Z(N + 1, nc);
  for (int i = 0; i <= N; ++i) {
    const double a = std::pow(static_cast<double>(i) / N, power);
    for (int j = 0; j < nc; ++j) Z(i, j) = (1 - a) * top.surface.points[j].z() + a * c;
  }
  return Z;
}

// A quadratic penalty always tolerates a small overshoot, so it aims 5 µm inside the limits;
// the figures are then checked against the limits themselves.
CostTerms cost_terms(const LayerParams& p) {
  const double inset = 0.005;
  return CostTerms{p.layer_height,
                   p.min_layer_height + inset,
                   p.max_layer_height - inset,
                   p.continuity_weight,
                   1e5,
                   std::tan(p.max_angle_deg * kDeg) - 0.01,
                   p.toolhead.clearance() - 0.05};
}

}  // namespace

bool stays_even(StackStart& s, const HeightField& top, const LayerParams& p) {
  const int N = s.result.stack.layers;
  if (N < 2 || p.max_iterations <= 0) return true;
  if (!s.coarse || !same_top(s.coarse->on, top)) s.coarse = coarse_grid(s, top, p);
  const Eigen::MatrixXd Z = starting_stack(top, N, s.result.stack.c, 1.0);
  const CostTerms terms = cost_terms(p);
  Eigen::MatrixXd grad;
  printability_cost(s.coarse->grid, Z, terms, &grad);
  // Ceres' GradientProblemSolver stops at once when the gradient's max norm is at most its
  // gradient_tolerance (1e-10 by default, finish_stack's).
  return grad.size() == 0 || grad.lpNorm<Eigen::Infinity>() <=
                                 ceres::GradientProblemSolver::Options().gradient_tolerance;
}

StackResult finish_stack(StackStart s, const TriangleMesh& mesh, const Patch& patch,
                         const HeightField& top, const LayerParams& p, double initial_power,
                         const Context& ctx) {
  StackResult out = std::move(s.result);
  out.needs_fit = false;
  LayerStack& st = out.stack;
  const int N = st.layers;
  const double zmin = s.zmin, zmax = s.zmax;
  const PatchRaster& raster = s.raster;
  StackGrid& grid = s.grid;
  std::vector<double>& H = s.H;
  std::vector<Vec2>& dH = s.dH;
  if (!s.fitted) {  // the checks read the rectangle: the same samples, now with the fit's basis
    build_stack_grid(grid, top, s.step, raster.mask, raster.origin, raster.cell, raster.nx,
                     raster.ny);
    for (const int k : s.off_facets)
      H[k] = top.height(grid.xy[k].x(), grid.xy[k].y()),
      dH[k] = top.gradient(grid.xy[k].x(), grid.xy[k].y());
  }
  if (!s.coarse || !same_top(s.coarse->on, top)) s.coarse = coarse_grid(s, top, p);
  const StackGrid& coarse = s.coarse->grid;
  // The blend's raster and the band's faceted top depend only on the facets, so they are built
  // while the optimiser runs, if not already (fit_for_plan builds them while the top is
  // fitted; on FoilCutter each takes about as long as a tenth of the slice).
  Background background;
  if (!s.blend_ready) background.run([&] { prepare_blend(s, mesh, patch, p); });

  // Starting stack and optimisation of the intermediate control heights.
  const int nc = top.surface.n_u * top.surface.n_v;
  Eigen::MatrixXd Z = starting_stack(top, N, st.c, initial_power);
  const CostTerms terms = cost_terms(p);
  // Each evaluation costs as much as the rest of the stack on a large patch (the bunny's
  // took 3 of them for an optimiser that found the even stack already optimal: the even
  // interpolation makes every t_ik and every gradient difference equal, so eq. 1's terms have
  // zero gradient there unless a limit is active). The cost at the start is the solver's first
  // evaluation (the same sum, in the same order) and the cost after is recomputed only when the
  // solver moved.
  // The top is the part's own, fixed: when it alone rises into the head within the block's
  // radius, no intermediate layers can save the stack, and the optimiser's work would be
  // thrown away (the bunny's patches 1, 7, 9 and 15; patch 1 took 100 iterations, 1 s). The
  // same figure as the full check below, whose maximum includes the top.
  Eigen::MatrixXd ends(2, nc);
  ends.row(0) = Z.row(0), ends.row(1) = Z.row(N);
  if (const Figures tf = measure(grid, ends, p, H, dH, st.c); tf.excess > 0) {
    out.failure = fmt2("a layer rises %.2f mm where the head is %.2f mm above the nozzle tip",
                       tf.rise, tf.rise_allow);
    return out;
  }
  std::optional<double> start;
  Eigen::MatrixXd best = Z;
  bool moved = false;
  if (N >= 2 && p.max_iterations > 0) {
    std::vector<double> x(static_cast<std::size_t>(N - 1) * nc);
    for (int i = 1; i < N; ++i)
      for (int j = 0; j < nc; ++j) x[(i - 1) * nc + j] = Z(i, j);
    const std::vector<double> x0 = x;
    ceres::GradientProblem problem(new StackObjective(coarse, Z, terms, &start));
    ceres::GradientProblemSolver::Options o;
    o.line_search_direction_type =
        p.optimizer == StackOptimizer::lbfgs ? ceres::LBFGS : ceres::STEEPEST_DESCENT;
    o.max_num_iterations = p.max_iterations;
    o.function_tolerance = 1e-7;
    o.logging_type = ceres::SILENT;
    nurbs::SolverProgress stop(ctx, "", 0, 0, p.max_iterations);
    o.callbacks.push_back(&stop);
    ceres::GradientProblemSolver::Summary sum;
    ceres::Solve(o, problem, x.data(), &sum);
    st.iterations = static_cast<int>(sum.iterations.size()) - 1;
    st.optimizer_message = sum.message;
    moved = x != x0;
    for (int i = 1; i < N; ++i)
      for (int j = 0; j < nc; ++j) best(i, j) = x[(i - 1) * nc + j];
  }
  st.cost_before = start ? *start : printability_cost(coarse, Z, terms, nullptr);
  st.cost_after = moved ? printability_cost(coarse, best, terms, nullptr) : st.cost_before;
  st.cost_optimised = st.cost_after;
  Figures f = measure(grid, best, p, H, dH, st.c);
  const auto ok = [&](const Figures& g) {
    return g.t_min >= p.min_layer_height - 1e-6 && g.t_max <= p.max_layer_height + 1e-6 &&
           g.slope <= p.max_angle_deg;
  };
  if (!ok(f) || !(st.cost_after <= st.cost_before)) {
    // The optimiser traded a limit for cost (or did not get there): keep the paper's even
    // interpolation, which meets the limits by the choice of c and N.
    const Eigen::MatrixXd even = starting_stack(top, N, st.c, 1.0);
    const Figures fe = measure(grid, even, p, H, dH, st.c);
    if (ok(fe)) {
      best = even, f = fe;
      st.cost_after = printability_cost(coarse, even, terms, nullptr);
      st.optimizer_message += " (result broke a limit; kept the even interpolation)";
    }
  }
  st.thickness_min = f.t_min;
  st.thickness_max = f.t_max;
  st.max_slope_deg = f.slope;
  st.max_block_rise = f.rise;
  if (f.t_min < p.min_layer_height - 1e-6 || f.t_max > p.max_layer_height + 1e-6) {
    out.failure = fmt2("layer thickness %.3f to %.3f mm leaves the limits", f.t_min, f.t_max);
    return out;
  }
  if (f.slope > p.max_angle_deg) {
    out.failure = fmt2("layer slope %.1f deg exceeds max_angle %.1f deg", f.slope, p.max_angle_deg);
    return out;
  }
  if (f.excess > 0) {
    out.failure = fmt2("a layer rises %.2f mm where the head is %.2f mm above the nozzle tip",
                       f.rise, f.rise_allow);
    return out;
  }
  for (int i = 0; i <= N; ++i) {
    HeightField layer = top;
    for (int j = 0; j < nc; ++j) layer.surface.points[j].z() = best(i, j);
    st.surfaces.push_back(std::move(layer));
  }
  Band& b = out.band;
  b.top = top;
  b.Z = best;
  b.c = st.c;
  b.N = N;
  b.T_bottom = st.T_bottom;

  // The top's range over the patch bounds it elsewhere (see Band::top_lo); a hair of slack
  // so points between grid samples on the patch are never touched.
  b.top_lo = zmin - 0.01, b.top_hi = zmax + 0.01;
  b.fade = s.fade;
  background.wait();
  set_blend(b, s.wide, s.blend);
  b.facets = std::move(s.band_facets);
  return out;
}

StackResult build_stack(const TriangleMesh& mesh, const Patch& patch, int patch_id,
                        const HeightField& top, const ColumnCaster& columns, const LayerParams& p,
                        const PlanarLayers& planar, double initial_power, const Context& ctx) {
  StackStart s = start_stack(mesh, patch, patch_id, top, columns, p, planar);
  if (!s.passed || s.result.needs_fit) return std::move(s.result);
  return finish_stack(std::move(s), mesh, patch, top, p, initial_power, ctx);
}

}  // namespace nonplanar::layers
