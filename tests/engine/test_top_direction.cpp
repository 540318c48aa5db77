// The direction of a shell's top-skin lines (src/engine/top_direction.hpp) on tops whose
// slopes are known.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/top_direction.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A plan whose top H is f on a 0.1 mm raster over [0, 40]², everywhere in its region.
layers::ShellPlan plan_over(const std::function<double(double, double)>& f) {
  layers::ShellPlan p;
  p.top.origin = Vec2(0, 0), p.top.cell = 0.1, p.top.nx = p.top.ny = 401;
  for (int i = 0; i < p.top.nx; ++i)
    for (int j = 0; j < p.top.ny; ++j) p.top.h.push_back(f(0.1 * i, 0.1 * j));
  return p;
}

double direction_of(const std::function<double(double, double)>& f, double max_deg = 45) {
  const TriangleMesh m = test::height_field_solid(f, 0, 40, 0, 40, 80, 80, -5);
  const auto d = top_slope_direction(m, plan_over(f), 2.0, max_deg);
  return d ? *d : -1;
}

TEST(TopDirection, RampsRunUpAndDownTheirSlope) {
  // Rising along x, along y, and along 30° (a 15° slope: tan 15° = 0.268).
  EXPECT_NEAR(direction_of([](double x, double) { return 5 + 0.268 * x; }), 0, 1e-6);
  EXPECT_NEAR(direction_of([](double, double y) { return 5 + 0.268 * y; }), 90, 1e-6);
  const double c = std::cos(M_PI / 6), s = std::sin(M_PI / 6);
  EXPECT_NEAR(direction_of([&](double x, double y) { return 20 + 0.268 * (c * x + s * y); }), 30,
              1e-6);
  // Falling along −x is the same line direction as rising along +x.
  EXPECT_NEAR(direction_of([](double x, double) { return 20 - 0.268 * x; }), 0, 1e-6);
}

TEST(TopDirection, AValleyAlongYRunsAcrossIt) {
  // Two slopes facing each other across x = 20: both fall and rise along x.
  EXPECT_NEAR(direction_of([](double x, double) { return 5 + 0.2 * std::abs(x - 20.2); }), 0, 1e-6);
}

TEST(TopDirection, NoDirectionWhereSlopesFaceEveryWayOrNone) {
  // A cone faces every way equally; a flat top and a top steeper than max_deg have no slope
  // counted.
  EXPECT_EQ(direction_of([](double x, double y) { return 20 - 0.3 * std::hypot(x - 20, y - 20); }),
            -1);
  EXPECT_EQ(direction_of([](double, double) { return 5.0; }), -1);
  EXPECT_EQ(direction_of([](double x, double) { return 5 + 0.268 * x; }, 10.0), -1);
}

TEST(TopDirection, OnlyFacetsOnTheShellsTopCount) {
  // The mesh's top rises along y; a plan whose H lies 1 mm above it (another top) sees none.
  const auto f = [](double, double y) { return 5 + 0.268 * y; };
  const TriangleMesh m = test::height_field_solid(f, 0, 40, 0, 40, 80, 80, -5);
  EXPECT_FALSE(top_slope_direction(m, plan_over([&](double x, double y) { return f(x, y) + 1; }),
                                   2.0, 45.0));
  EXPECT_TRUE(top_slope_direction(m, plan_over(f), 2.0, 45.0));
}

}  // namespace
}  // namespace nonplanar
