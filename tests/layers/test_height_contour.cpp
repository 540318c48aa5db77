// region_at_least (src/layers/height_contour.hpp) on height fields whose level sets are known.
#include <gtest/gtest.h>

#include <cmath>

#include "layers/height_contour.hpp"

namespace nonplanar {
namespace {

layers::FacetedTop raster(int nx, int ny, double cell, double (*h)(double, double)) {
  layers::FacetedTop t;
  t.origin = {0, 0}, t.cell = cell, t.nx = nx, t.ny = ny;
  t.h.resize(static_cast<std::size_t>(nx) * ny);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) t.h[static_cast<std::size_t>(i) * ny + j] = h(i * cell, j * cell);
  return t;
}

TEST(HeightContour, RampCutsItsBoxAtTheLevel) {
  // H = x on [0, 10] × [0, 5]: H >= 3.05 is [3.05, 10] × [0, 5] (the level between nodes).
  const auto t = raster(101, 51, 0.1, [](double x, double) { return x; });
  const auto r = layers::region_at_least(t, 3.05);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(area(r), 6.95 * 5.0, 1e-6);
  EXPECT_TRUE(layers::region_at_least(t, 10.5).empty());
  EXPECT_NEAR(area(layers::region_at_least(t, -1.0)), 50.0, 1e-6);
}

TEST(HeightContour, DomeGivesADiscAndAPitGivesAHole) {
  // A cone of slope 1 around (5, 5): H >= 7 is the disc of radius 3.
  const auto dome =
      raster(101, 101, 0.1, [](double x, double y) { return 10.0 - std::hypot(x - 5, y - 5); });
  const auto disc = layers::region_at_least(dome, 7.0);
  ASSERT_EQ(disc.size(), 1u);
  EXPECT_TRUE(disc[0].holes.empty());
  EXPECT_NEAR(area(disc), M_PI * 9.0, 0.02);
  // Upside down: H >= 3 is the box minus that disc.
  const auto pit =
      raster(101, 101, 0.1, [](double x, double y) { return std::hypot(x - 5, y - 5); });
  const auto ring = layers::region_at_least(pit, 3.0);
  ASSERT_EQ(ring.size(), 1u);
  EXPECT_EQ(ring[0].holes.size(), 1u);
  EXPECT_NEAR(area(ring), 100.0 - M_PI * 9.0, 0.02);
}

}  // namespace
}  // namespace nonplanar
