// The stack's faceted top (src/layers/faceted_top.hpp) on a coarse sphere, the case it exists
// for: 1280 facets, the top cap printable, facets up to 0.1 mm below the sphere through their
// vertices.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/column_caster.hpp"
#include "layers/faceted_top.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

struct Cap {
  TriangleMesh mesh = test::icosphere({0, 0, 15.5}, 15.5, 3);
  Analysis analysis = *analyze(mesh, {}, {});
  const Patch& patch() const {
    for (const Patch& p : analysis.patches)
      if (p.needs_nonplanar()) return p;
    return analysis.patches.front();
  }
};

TEST(FacetedTop, LiesOnTheFacetsAndStaysInTheirRangePastTheRim) {
  const Cap cap;
  const Patch& patch = cap.patch();
  ASSERT_TRUE(patch.needs_nonplanar());
  const layers::FacetedTop ft = layers::faceted_top(cap.mesh, patch, 0.1, 3.0, 0.3);
  ASSERT_FALSE(ft.empty());
  const ColumnCaster cols(cap.mesh);
  // At the raster's nodes well inside the cap (its rim is about 8.7 mm from the axis): the
  // facets' own heights; between nodes, within a few µm of them.
  double at_nodes = 0, between = 0;
  for (int i = 0; i < ft.nx; ++i)
    for (int j = 0; j < ft.ny; ++j) {
      const double x = ft.origin.x() + i * ft.cell, y = ft.origin.y() + j * ft.cell;
      if (std::hypot(x, y) > 7) continue;
      at_nodes = std::max(at_nodes, std::abs(ft.height(x, y) - cols.crossings(x, y).back()));
    }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int k = 0; k < 2000; ++k) {
    const double x = u(rng), y = u(rng);
    between = std::max(between, std::abs(ft.height(x, y) - cols.crossings(x, y).back()));
  }
  EXPECT_LT(at_nodes, 1e-9);
  EXPECT_LT(between, 0.005);
  // Off the patch H carries the rim outward within the patch's height range, and levels off.
  const double lowest = patch.z_min;
  for (double h : ft.h) {
    EXPECT_GE(h, lowest - 1e-9);
    EXPECT_LE(h, patch.z_max + 1e-9);
  }
  const double far = ft.height(ft.origin.x() + 0.2, ft.origin.y() + 0.2);
  const double far2 = ft.height(ft.origin.x() + 0.7, ft.origin.y() + 0.2);
  EXPECT_LT(std::abs(far2 - far) / 0.5, 0.1);
}

TEST(FacetSamples, ExactHeightsAndSlopesOnTheFacets) {
  const Cap cap;
  const Patch& patch = cap.patch();
  std::vector<Vec2> xy;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-7, 7);
  while (xy.size() < 500) {  // well inside the cap's rim (about 8.7 mm from the axis)
    const Vec2 p(u(rng), u(rng));
    if (p.norm() < 7) xy.push_back(p);
  }
  xy.emplace_back(40, 40);  // far from every triangle of the cap
  std::vector<char> want(xy.size(), 1);
  want[1] = 0;
  const layers::FacetSamples fs = layers::facet_samples(cap.mesh, patch, xy, want);
  const ColumnCaster cols(cap.mesh);
  const double tan_max = std::tan(patch.max_slope_deg * M_PI / 180.0);
  for (std::size_t k = 0; k + 1 < xy.size(); ++k) {
    if (k == 1) {
      EXPECT_TRUE(std::isnan(fs.h[k]));
      continue;
    }
    const double top = cols.crossings(xy[k].x(), xy[k].y()).back();
    EXPECT_NEAR(fs.h[k], top, 1e-9);
    EXPECT_LE(fs.slope[k].norm(), tan_max + 1e-9);
    // The slope is the facet's: a step of 1 µm along it stays on the mesh.
    const Vec2 d = 1e-6 * fs.slope[k].normalized();
    if (fs.slope[k].norm() > 1e-3) {
      EXPECT_NEAR(cols.crossings(xy[k].x() + d.x(), xy[k].y() + d.y()).back() - top,
                  fs.slope[k].dot(d), 1e-9);
    }
  }
  EXPECT_TRUE(std::isnan(fs.h.back()));
  EXPECT_NEAR(fs.h_lo, patch.z_min, 1e-12);
  EXPECT_NEAR(fs.h_hi, patch.z_max, 1e-12);
}

}  // namespace
}  // namespace nonplanar
