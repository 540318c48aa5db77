// check_print on moves built by hand: collisions found where a nozzle would plough through
// earlier material and nowhere else, thickness between stacked layers, and the safety
// gate's collisions-only mode agreeing with the full check.
#include <gtest/gtest.h>

#include <cmath>

#include "nonplanar/check.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// Parallel lines 0.45 mm apart filling [0, w] x [0, d] at height z: one layer.
void raster(std::vector<PrintMove>& out, int layer, double w, double d, double z) {
  for (double y = 0; y <= d + 1e-9; y += 0.45) {
    PrintMove m;
    m.from = {0, y, z}, m.to = {w, y, z};
    m.filament = 0.03 * w, m.extruding = true, m.layer = layer, m.type = "Solid infill";
    out.push_back(m);
  }
}

TEST(CheckPrint, StackedLayersHaveTheirThicknessAndNoCollision) {
  std::vector<PrintMove> moves;
  for (int l = 0; l < 4; ++l) raster(moves, l, 10, 10, 0.2 * (l + 1));
  auto f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
  EXPECT_NEAR(f->thickness_min, 0.2, 1e-6);
  EXPECT_NEAR(f->thickness_max, 0.2, 1e-6);
  EXPECT_NEAR(f->steepest_deg, 0, 1e-9);
}

TEST(CheckPrint, ThicknessOfASlopedLayerOverALineAcrossIt) {
  // Layer 0 is one line along y at x = 5, z = 0.2 + 0.5 y; layer 1 is a raster along x sloped
  // the same way, z = 0.4 + 0.5 y: 0.2 mm above layer 0 wherever they cross. (A plane fit
  // through lines 0.15 mm apart read the edge of such a layer 0.275 mm thick.)
  std::vector<PrintMove> moves;
  PrintMove line;
  line.from = {5, -0.4, 0.0}, line.to = {5, 0.4, 0.4};
  line.filament = 0.03, line.extruding = true, line.layer = 0, line.type = "Solid infill";
  moves.push_back(line);
  for (double y = -0.3; y <= 0.3 + 1e-9; y += 0.15) {
    PrintMove m;
    m.from = {0, y, 0.4 + 0.5 * y}, m.to = {10, y, 0.4 + 0.5 * y};
    m.filament = 0.3, m.extruding = true, m.layer = 1, m.type = "Solid infill";
    moves.push_back(m);
  }
  auto f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->thickness_min, 0.2, 1e-9);
  EXPECT_NEAR(f->thickness_max, 0.2, 1e-9);
  EXPECT_NEAR(f->thickness_min_at.x(), 5, 1e-9);
}

TEST(CheckPrint, NozzleBelowEarlierMaterialCollides) {
  // Layer 0 is a raised ridge at z = 2 over x in [0, 10] (as a curved layer could leave);
  // layer 1 then prints flat at z = 0.4 right beside it: the nozzle cone meets the ridge.
  std::vector<PrintMove> moves;
  raster(moves, 0, 10, 1, 2.0);
  PrintMove m;
  m.from = {0, 1.6, 0.4}, m.to = {10, 1.6, 0.4};
  m.filament = 0.3, m.extruding = true, m.layer = 1, m.line = 42;
  moves.push_back(m);
  auto f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_GT(f->collisions, 40u);  // every sample along the 10 mm line (0.2 mm apart)
  EXPECT_EQ(f->first_collision_line, 42);
  EXPECT_NEAR(f->first_collision.z(), 0.4, 1e-9);
  // Far enough away that the 45° cone clears the ridge: (5 - 0.4) tan 45° > 2 - 0.4.
  moves.back().from.y() = moves.back().to.y() = 1 + 5;
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
  // Above the ridge: nothing to hit.
  moves.back().from = {0, 0.5, 2.2}, moves.back().to = {10, 0.5, 2.2};
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
}

// A travel goes where a head can: not into material printed before it (a layer change mapped
// where a core ended on a support column once sent the nozzle down through it), not under the
// bed; over the material, or beside a ridge the cone clears, is no collision.
TEST(CheckPrint, ATravelIntoEarlierMaterialOrUnderTheBedCollides) {
  std::vector<PrintMove> moves;
  raster(moves, 0, 10, 1, 2.0);  // a ridge 2 mm high
  PrintMove t;
  t.from = {5, 0.5, 3}, t.to = {5, 0.5, 0.4};  // straight down into it
  t.layer = 1, t.line = 7;
  moves.push_back(t);
  auto f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_GE(f->collisions, 3u);  // 0.5 mm apart, from 2 mm down
  EXPECT_EQ(f->first_collision_line, 7);
  EXPECT_LT(f->first_collision.z(), 2.0);
  moves.back().to = {5, 0.5, 2.2};  // down onto it
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
  moves.back().from = {-20, 8, 2.2}, moves.back().to = {30, 8, 2.2};  // across, 8 mm off
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
  moves.back().from = {30, 30, 1}, moves.back().to = {30, 30, -0.3};  // under the bed
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 1u);
  EXPECT_NEAR(f->first_collision.z(), -0.3, 1e-9);
  // A wipe retraces its extrusion's layer though written after the next layer change: only
  // the bed is its business.
  moves.back().wipe = true;
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 1u);
  moves.back().from = {5, 0.5, 3}, moves.back().to = {5, 0.5, 0.4};
  f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
}

TEST(CheckPrint, CollisionSearchAloneCountsTheSame) {
  std::vector<PrintMove> moves;
  raster(moves, 0, 10, 3, 1.5);
  raster(moves, 1, 12, 6, 0.4);  // partly beside, partly under the raised layer
  raster(moves, 2, 12, 6, 1.9);
  const auto a = check_print(moves, nullptr, {}, {});
  const auto b = find_collisions(moves, {}, nullptr, {});
  ASSERT_TRUE(a && b);
  EXPECT_GT(a->collisions, 0u);
  EXPECT_EQ(a->collisions, b->collisions);
  EXPECT_EQ(a->first_collision_line, b->first_collision_line);
  EXPECT_EQ(a->collision_points.size(), b->points.size());
  EXPECT_EQ(a->extrusions, b->extrusions);
  // Looked at only where x < 5: fewer, and none at x >= 5.
  const auto c = find_collisions(moves, {}, [](const Vec3& p) { return p.x() < 5; }, {});
  ASSERT_TRUE(c);
  EXPECT_LT(c->collisions, a->collisions);
  for (const Vec3& p : c->points) EXPECT_LT(p.x(), 5.0);
}

// A top surface with other material high above it (an arch, a second body): the layer that
// prints the surface is the one at its height, not the highest one over it.
TEST(CheckPrint, DeviationIgnoresMaterialFarAbove) {
  TriangleMesh mesh = test::box({0, 0, 0}, {10, 10, 0.2});
  const TriangleMesh plate = test::box({0, 0, 4.8}, {10, 10, 5.0});
  const int off = static_cast<int>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), plate.vertices.begin(), plate.vertices.end());
  for (auto f : plate.faces) mesh.faces.push_back({f[0] + off, f[1] + off, f[2] + off});
  std::vector<PrintMove> moves;
  raster(moves, 0, 10, 10, 0.2);
  raster(moves, 1, 10, 10, 5.0);  // (its support is not the point here)
  auto f = check_print(moves, &mesh, {}, {});
  ASSERT_TRUE(f);
  EXPECT_GT(f->covered_samples, 0.9 * static_cast<double>(f->surface_samples));
  EXPECT_LT(f->deviation_max, 1e-6);  // both tops printed exactly at their heights
}

// The top's samples are spread by area, not by facet: a 10 x 10 mm top whose left half is
// 800 tiny facets and right half 2 large ones, printed right (z = 0.2) over the right half
// and 0.1 mm too high over the left, is within 0.03 mm on the right half's samples less a
// strip of about 0.7 mm where the height plane takes points of both halves: 0.43. (Taking
// every facet once at least gave the left half 800 of 900 samples: a share of 0.05.)
TEST(CheckPrint, TopSamplesAreSpreadByAreaAndCountedWithinTheTolerance) {
  TriangleMesh top;
  auto quad = [&](double x0, double y0, double x1, double y1) {
    const int b = static_cast<int>(top.vertices.size());
    top.vertices.push_back({x0, y0, 0.2}), top.vertices.push_back({x1, y0, 0.2});
    top.vertices.push_back({x1, y1, 0.2}), top.vertices.push_back({x0, y1, 0.2});
    top.faces.push_back({b, b + 1, b + 2}), top.faces.push_back({b, b + 2, b + 3});
  };
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) quad(0.25 * i, 0.5 * j, 0.25 * (i + 1), 0.5 * (j + 1));
  quad(5, 0, 10, 10);
  std::vector<PrintMove> moves;
  for (double y = 0; y <= 10 + 1e-9; y += 0.45) {
    PrintMove m;
    m.extruding = true, m.layer = 0, m.type = "Top solid infill", m.filament = 0.1;
    m.from = {0, y, 0.3}, m.to = {5, y, 0.3};
    moves.push_back(m);
    m.from = {5.2, y, 0.2}, m.to = {10, y, 0.2};
    moves.push_back(m);
  }
  CheckParams cp;
  auto f = check_print(moves, &top, cp, {});
  ASSERT_TRUE(f);
  EXPECT_NEAR(static_cast<double>(f->surface_samples), 200, 12);  // 2 per mm² of 100 mm²
  EXPECT_EQ(f->covered_samples, f->surface_samples);
  EXPECT_NEAR(f->within_share, 0.43, 0.03);
  // Only facets at least 2° from horizontal: this flat top has none.
  cp.min_angle_deg = 2;
  f = check_print(moves, &top, cp, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->surface_samples, 0u);
  EXPECT_EQ(f->within_share, 0);
}

}  // namespace
}  // namespace nonplanar
