// check_print on moves built by hand: collisions found where a nozzle would plough through
// earlier material and nowhere else, thickness between stacked layers, and the safety
// gate's collisions-only mode agreeing with the full check.
#include <gtest/gtest.h>

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

TEST(CheckPrint, ThicknessOverTheEdgeOfASlopedLayerBelow) {
  // Layer 0 is one line along x at y = 0, z = 0.2; layer 1 is a raster sloped in y,
  // z = 0.4 + 0.5 y: 0.2 mm above layer 0 where it lies. (Measured from the line's nearest
  // point, a line of layer 1 at y = 0.15 was 0.275 mm thick.)
  std::vector<PrintMove> moves;
  raster(moves, 0, 10, 0, 0.2);
  for (double y = -0.3; y <= 0.3 + 1e-9; y += 0.15) {
    PrintMove m;
    m.from = {0, y, 0.4 + 0.5 * y}, m.to = {10, y, 0.4 + 0.5 * y};
    m.filament = 0.3, m.extruding = true, m.layer = 1, m.type = "Solid infill";
    moves.push_back(m);
  }
  auto f = check_print(moves, nullptr, {}, {});
  ASSERT_TRUE(f);
  EXPECT_NEAR(f->thickness_min, 0.2, 1e-6);
  EXPECT_NEAR(f->thickness_max, 0.2, 1e-6);
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

}  // namespace
}  // namespace nonplanar
