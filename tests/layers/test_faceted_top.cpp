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

// The slope bound holds on the cap's top between random nearby points (H's change over a
// step is at most the bound over the step's box times its length), is exact on a plane, and
// is 0 over a flat tile beside a steep one.
TEST(TopSlopeBound, BoundsTheTopsChangeAndIsTightOnAPlane) {
  const Cap cap;
  const layers::FacetedTop ft = layers::faceted_top(cap.mesh, cap.patch(), 0.1, 3.0, 0.3);
  const layers::TopSlopeBound bound(ft);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1), d(-2, 2);
  const Vec2 size(ft.cell * (ft.nx - 1), ft.cell * (ft.ny - 1));
  for (int k = 0; k < 20000; ++k) {
    const Vec2 p = ft.origin + Vec2(u(rng) * size.x(), u(rng) * size.y());
    const Vec2 q = p + Vec2(d(rng), d(rng));
    const double L = bound.over(p.cwiseMin(q), p.cwiseMax(q));
    ASSERT_LE(std::abs(ft.height(q.x(), q.y()) - ft.height(p.x(), p.y())),
              L * (q - p).norm() + 1e-12)
        << p.transpose() << " -> " << q.transpose();
  }
  layers::FacetedTop plane;
  plane.cell = 0.5, plane.nx = 40, plane.ny = 40;  // 20 mm, tiles of 8 mm
  for (int i = 0; i < plane.nx; ++i)
    for (int j = 0; j < plane.ny; ++j)
      plane.h.push_back(i < 32 ? 0.3 * i * plane.cell + 0.4 * j * plane.cell : 1e3);
  const layers::TopSlopeBound on_plane(plane);
  EXPECT_NEAR(on_plane.over({1, 1}, {3, 3}), 0.5, 1e-12);
  EXPECT_GT(on_plane.over({1, 1}, {19, 3}), 100);  // the cliff at x = 15.5-16 mm
  plane.h.assign(plane.h.size(), 2.0);
  plane.h.back() = 50;  // one node, in the last tile
  const layers::TopSlopeBound flat(plane);
  EXPECT_EQ(flat.over({0, 0}, {7, 7}), 0.0);
  EXPECT_GT(flat.over({0, 0}, {30, 30}), 90);  // past the edge: the edge's cells
  plane.h[5] = std::nan("");
  EXPECT_TRUE(std::isinf(layers::TopSlopeBound(plane).over({0, 0}, {1, 1})));
}

// A mask's value is what a FacetedTop of its ±1 gives, to the bit, inside the raster and past
// its edge (a shell's region was such a raster of doubles).
TEST(NodeMask, ValuesAreTheBilinearOfItsSigns) {
  layers::NodeMask m;
  m.origin = {3, -2}, m.cell = 0.13, m.nx = 37, m.ny = 23;
  std::mt19937 rng(7);
  for (int k = 0; k < m.nx * m.ny; ++k) m.in.push_back(rng() % 3 == 0 ? -1 : 1);
  const layers::FacetedTop t = m.as_top();
  ASSERT_EQ(t.h.size(), m.in.size());
  std::uniform_real_distribution<double> x(2, 9), y(-3, 2);
  int inside = 0, outside = 0;
  for (int k = 0; k < 20000; ++k) {
    const double px = x(rng), py = y(rng);
    const double v = m.value(px, py);
    ASSERT_EQ(v, t.height(px, py)) << px << ", " << py;
    (v >= 0 ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 1000);
  EXPECT_GT(outside, 1000);
  EXPECT_EQ(m.value(3, -2), m.in[0]);  // a node
}

// A mask's signed distance has the mask's sign everywhere (the same cut), is ±1 next to the
// other side, is the chessboard distance at nodes, and changes by at most one a cell (what
// the engine route's core clip steps by).
TEST(NodeDistance, HasTheMasksSignAndIsTheChessboardDistance) {
  layers::NodeMask m;
  m.origin = {3, -2}, m.cell = 0.13, m.nx = 37, m.ny = 23;
  std::mt19937 rng(11);
  for (int i = 0; i < m.nx; ++i)  // a disc of radius 8 cells with a few holes and specks
    for (int j = 0; j < m.ny; ++j) {
      const bool in = std::hypot(i - 18, j - 11) < 8;
      m.in.push_back((in != (rng() % 23 == 0)) ? 1 : -1);
    }
  const layers::NodeDistance d = layers::signed_distance(m);
  ASSERT_EQ(d.d.size(), m.in.size());
  auto at = [&](int i, int j) {
    return static_cast<std::size_t>(i) * 23 + static_cast<std::size_t>(j);
  };
  for (int i = 0; i < m.nx; ++i)
    for (int j = 0; j < m.ny; ++j) {
      int nearest = 1 << 20;  // brute force: the chessboard distance to the other side
      for (int a = 0; a < m.nx; ++a)
        for (int b = 0; b < m.ny; ++b)
          if (m.in[at(a, b)] != m.in[at(i, j)])
            nearest = std::min(nearest, std::max(std::abs(a - i), std::abs(b - j)));
      ASSERT_EQ(d.d[at(i, j)], m.in[at(i, j)] > 0 ? -nearest : nearest) << i << ", " << j;
      if (i + 1 < m.nx && m.in[at(i + 1, j)] == m.in[at(i, j)]) {
        EXPECT_LE(std::abs(d.d[at(i + 1, j)] - d.d[at(i, j)]), 1);
      }
    }
  std::uniform_real_distribution<double> x(2, 9), y(-3, 2);
  for (int k = 0; k < 20000; ++k) {
    const double px = x(rng), py = y(rng);
    ASSERT_LE(d.value(px, py) * m.value(px, py), 0) << px << ", " << py;  // opposite signs
    ASSERT_EQ(d.value(px, py) == 0, m.value(px, py) == 0) << px << ", " << py;
  }
}

}  // namespace
}  // namespace nonplanar
