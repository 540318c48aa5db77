#include <gtest/gtest.h>

#include <random>

#include "layers/patch_raster.hpp"
#include "layers/printability_cost.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A 12 × 10 mm sine bump's patch, its fitted top (at most 7 controls a side) and the cost's
// grid over the patch's rectangle at 1 mm.
struct Bump {
  SurfaceFit fit;
  layers::StackGrid grid;
  int controls() const { return fit.surface.surface.n_u * fit.surface.surface.n_v; }
};
Bump bump(double amplitude) {
  const TriangleMesh m = test::height_field_solid(
      [amplitude](double x, double y) { return 6 + amplitude * std::sin(x / 3) * std::cos(y / 4); },
      0, 12, 0, 10, 24, 20);
  const Analysis a = *analyze(m, {}, {});
  FitParams fp;
  fp.max_control = 7;
  Bump b;
  b.fit = *fit_patch(m, a.patches[0], fp, {});
  const layers::PatchRaster r = layers::rasterize_patch(m, a.patches[0], 0.25, 0.0);
  layers::build_stack_grid(b.grid, b.fit.surface, 1.0, r.mask, r.origin, r.cell, r.nx, r.ny);
  return b;
}

// The analytic gradient of the cost against central differences, on a stack whose terms
// are all active: thickness outside the limits, steep layers, a tight heater clearance.
TEST(PrintabilityCost, GradientMatchesFiniteDifferences) {
  Bump b = bump(1.0);
  const SurfaceFit& fit = b.fit;
  layers::StackGrid& g = b.grid;
  g.pair_within(3.0, 1.0);
  ASSERT_FALSE(g.block_pairs.empty());
  const int nc = b.controls();
  const int N = 5;
  Eigen::MatrixXd Z(N + 1, nc);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> jitter(-0.6, 0.6);
  for (int i = 0; i <= N; ++i)
    for (int j = 0; j < nc; ++j)
      Z(i, j) = (1.0 - i / 5.0) * fit.surface.surface.points[j].z() + i / 5.0 * 3.0 +
                (i > 0 && i < N ? jitter(rng) : 0.0);
  const layers::CostTerms terms{0.2, 0.1, 0.3, 0.05, 1e3, std::tan(10 * M_PI / 180), 0.3};
  Eigen::MatrixXd grad;
  const double c0 = layers::printability_cost(g, Z, terms, &grad);
  ASSERT_GT(c0, 0);
  ASSERT_EQ(grad.rows(), N - 1);
  double worst = 0, scale = 0;
  for (int i = 1; i < N; ++i)
    for (int j = 0; j < nc; j += 3) {
      const double e = 1e-6;
      Eigen::MatrixXd Zp = Z, Zm = Z;
      Zp(i, j) += e;
      Zm(i, j) -= e;
      const double fd = (layers::printability_cost(g, Zp, terms, nullptr) -
                         layers::printability_cost(g, Zm, terms, nullptr)) /
                        (2 * e);
      worst = std::max(worst, std::abs(fd - grad(i - 1, j)));
      scale = std::max(scale, std::abs(fd));
    }
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(worst, 1e-5 * scale);
}

// The slope term against a sum worked out here from the grid's basis: with g < 0 (a limit
// under 0.6°) every intermediate layer on the patch pays μ a_k (|∇S_i| − g)²; with a limit
// no layer reaches, none does. Off the patch nothing is paid.
TEST(PrintabilityCost, SlopeTermOverEveryLayerBelowANegativeLimit) {
  const Bump b = bump(0.8);
  const SurfaceFit& fit = b.fit;
  const layers::StackGrid& g = b.grid;
  const int nc = b.controls(), N = 4;
  Eigen::MatrixXd Z(N + 1, nc);
  for (int i = 0; i <= N; ++i)
    for (int j = 0; j < nc; ++j)
      Z(i, j) = (1.0 - i / 4.0) * fit.surface.surface.points[j].z() + i / 4.0 * 3.0;
  const double mu = 10.0, g_neg = -0.01;
  const layers::CostTerms loose{0.2, 0.1, 0.3, 0.05, mu, 1e6};
  const layers::CostTerms tight{0.2, 0.1, 0.3, 0.05, mu, g_neg};
  double expected = 0;
  int on = 0;
  for (std::size_t k = 0; k < g.xy.size(); ++k) {
    if (!g.on_patch[k]) continue;
    ++on;
    for (int i = 1; i < N; ++i) {
      double sx = 0, sy = 0;
      for (int c = 0; c < g.m; ++c) {
        sx += g.Rx[k * g.m + c] * Z(i, g.control(static_cast<int>(k), c));
        sy += g.Ry[k * g.m + c] * Z(i, g.control(static_cast<int>(k), c));
      }
      const double over = std::hypot(sx, sy) - g_neg;
      expected += g.area[k] * mu * over * over;
    }
  }
  ASSERT_GT(on, 20);
  ASSERT_LT(on, static_cast<int>(g.xy.size()));  // some samples lie off the patch
  const double paid = layers::printability_cost(g, Z, tight, nullptr) -
                      layers::printability_cost(g, Z, loose, nullptr);
  EXPECT_GT(expected, 1.0);
  EXPECT_NEAR(paid, expected, 1e-9 * expected);
}

}  // namespace
}  // namespace nonplanar
