#include <gtest/gtest.h>

#include <atomic>

#include <cmath>
#include <functional>

#include "nonplanar/patch_fit.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using Fn = std::function<double(double, double)>;

struct Analytic {
  TriangleMesh mesh;
  Patch patch;  // the top
};

// A height-field block meshed at `cells` per side over [-L, L]²; its top is one patch.
Analytic analytic(const Fn& f, double L, int cells) {
  Analytic a;
  a.mesh = test::height_field_solid(f, -L, L, -L, L, cells, cells);
  auto an = analyze(a.mesh, {}, {});
  EXPECT_TRUE(an);
  EXPECT_FALSE(an->patches.empty());
  a.patch = an->patches.front();
  EXPECT_EQ(a.patch.faces.size(), 2u * cells * cells);
  return a;
}

// RMS and max of |S − f| on a dense grid inside the footprint.
std::pair<double, double> error_vs(const HeightField& s, const Fn& f, double L) {
  double ss = 0, mx = 0;
  int n = 0;
  for (int i = 0; i <= 200; ++i)
    for (int j = 0; j <= 200; ++j) {
      const double x = -L + 2 * L * i / 200.0, y = -L + 2 * L * j / 200.0;
      const double d = s.height(x, y) - f(x, y);
      ss += d * d;
      mx = std::max(mx, std::abs(d));
      ++n;
    }
  return {std::sqrt(ss / n), mx};
}

void expect_fits(const Fn& f, double L, int cells, const FitParams& params = {}) {
  const Analytic a = analytic(f, L, cells);
  auto fit = fit_patch(a.mesh, a.patch, params, {});
  ASSERT_TRUE(fit) << fit.error().message;
  const auto [rms, mx] = error_vs(fit->surface, f, L);
  EXPECT_LE(rms, 0.005) << "control " << fit->surface.surface.n_u << "x"
                        << fit->surface.surface.n_v;
  EXPECT_LE(mx, 0.02);
  EXPECT_LE(fit->rms_error, 0.005);  // against the triangles themselves
  EXPECT_TRUE(fit->surface.surface.valid());
}

TEST(Fit, ParaboloidCap) {
  expect_fits([](double x, double y) { return 12 - (x * x + y * y) / 60.0; }, 12, 96);
}

TEST(Fit, Saddle) {
  expect_fits([](double x, double y) { return 10 + (x * x - y * y) / 50.0; }, 10, 80);
}

TEST(Fit, SineWavesNeedRefinement) {
  const Fn f = [](double x, double y) {
    return 8 + 1.2 * std::sin(2 * M_PI * x / 18) * std::cos(2 * M_PI * y / 22);
  };
  expect_fits(f, 15, 120);
  const Analytic a = analytic(f, 15, 120);
  auto fit = fit_patch(a.mesh, a.patch, {}, {});
  ASSERT_TRUE(fit);
  EXPECT_GT(fit->refinements, 0);
  EXPECT_GT(fit->surface.surface.n_u, FitParams{}.initial_spans + 3);
}

TEST(Fit, FreeWeightsBeatFixedWeightsOnASphericalCap) {
  const double R = 20;
  const Fn cap = [R](double x, double y) { return std::sqrt(R * R - x * x - y * y); };
  const Analytic a = analytic(cap, 7, 70);
  FitParams fixed;
  fixed.initial_spans = 1;  // one span: the same 4×4 grid for both fits
  fixed.max_control = 4;
  fixed.free_weights = false;
  fixed.nonlinear = NonlinearSolver::none;
  fixed.refine_only_if_needed = false;  // compare on the same grid even if one is good enough
  FitParams free = fixed;
  free.free_weights = true;
  free.nonlinear = NonlinearSolver::levenberg_marquardt;
  auto f0 = fit_patch(a.mesh, a.patch, fixed, {});
  auto f1 = fit_patch(a.mesh, a.patch, free, {});
  ASSERT_TRUE(f0 && f1);
  EXPECT_EQ(f0->surface.surface.n_u, 4);
  EXPECT_EQ(f1->surface.surface.n_u, 4);
  EXPECT_LT(f1->rms_error, 0.8 * f0->rms_error);
  EXPECT_LT(f1->nonlinear.final_cost, f1->nonlinear.initial_cost);
  EXPECT_GT(f1->nonlinear.iterations, 0);
  EXPECT_FALSE(f1->nonlinear.termination.empty());
  bool some_weight_moved = false;
  for (double w : f1->surface.surface.weights) {
    EXPECT_GE(w, free.weight_min);
    EXPECT_LE(w, free.weight_max);
    some_weight_moved |= std::abs(w - 1) > 1e-3;
  }
  EXPECT_TRUE(some_weight_moved);

  FitParams gn = free;
  gn.nonlinear = NonlinearSolver::gauss_newton_line_search;
  auto f2 = fit_patch(a.mesh, a.patch, gn, {});
  ASSERT_TRUE(f2);
  EXPECT_LT(f2->rms_error, 0.8 * f0->rms_error);
  EXPECT_LE(f2->nonlinear.final_cost, f2->nonlinear.initial_cost);
}

// The nonlinear solvers report progress per iteration and stop when the run is cancelled
// (#21 item 8): here the flag is raised by the first progress report from inside the solve
// (the fit's stages before it report at most 0.8).
TEST(Fit, NonlinearSolversStopWhenCancelled) {
  const double R = 20;
  const Fn cap = [R](double x, double y) { return std::sqrt(R * R - x * x - y * y); };
  const Analytic a = analytic(cap, 7, 70);
  for (const NonlinearSolver solver :
       {NonlinearSolver::levenberg_marquardt, NonlinearSolver::gauss_newton_line_search}) {
    FitParams p;
    p.initial_spans = 1, p.max_control = 4, p.refine_only_if_needed = false;
    p.nonlinear = solver;
    std::atomic<bool> stop{false};
    int reports_inside = 0;
    Context ctx;
    ctx.cancel_flag = &stop;
    ctx.on_progress = [&](std::string_view stage, double f) {
      if (stage == "fit" && f > 0.8 && f < 1.0) ++reports_inside, stop = true;
    };
    auto r = fit_patch(a.mesh, a.patch, p, ctx);
    ASSERT_FALSE(r);
    EXPECT_EQ(r.error().status, Status::cancelled);
    EXPECT_EQ(reports_inside, 1);  // stopped at the next look
  }
}

TEST(Fit, RejectsBadParameters) {
  const Analytic a = analytic([](double x, double) { return 3 + 0.1 * x; }, 5, 10);
  FitParams p;
  p.tolerance = -1;
  auto r = fit_patch(a.mesh, a.patch, p, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::invalid_argument);
  EXPECT_EQ(r.error().message.rfind("fit_tolerance:", 0), 0u);
}

}  // namespace
}  // namespace nonplanar
