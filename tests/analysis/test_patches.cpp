#include <gtest/gtest.h>

#include <cmath>

#include "nonplanar/analysis.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

std::size_t nonplanar_patches(const TriangleMesh& m, const AnalysisParams& p = {}) {
  auto a = analyze(m, p, {});
  EXPECT_TRUE(a) << a.error().message;
  std::size_t n = 0;
  for (const Patch& patch : a->patches) n += patch.needs_nonplanar();
  return n;
}

TEST(Patches, TwoCurvedTowersOnAPlate) {
  TriangleMesh m = test::box({0, 0, 0}, {80, 40, 3});
  auto dome = [](double cx, double cy) {
    return [=](double x, double y) {
      return 18 + 2.0 * std::cos(0.1 * (x - cx)) * std::cos(0.1 * (y - cy));
    };
  };
  test::append(m, test::height_field_solid(dome(20, 20), 10, 30, 10, 30, 16, 16, 3));
  test::append(m, test::height_field_solid(dome(60, 20), 50, 70, 10, 30, 16, 16, 3));
  auto a = analyze(m, {}, {});
  ASSERT_TRUE(a);
  EXPECT_EQ(nonplanar_patches(m), 2u);
  // The plate's flat top is a patch that needs no non-planar layers.
  std::size_t flat = 0;
  for (const Patch& p : a->patches) flat += p.verdict == PatchVerdict::flat;
  EXPECT_EQ(flat, 1u);
  for (const Patch& p : a->patches)
    if (p.needs_nonplanar()) {
      EXPECT_NEAR(p.area, 400.0, 15.0);  // the 20×20 dome, slightly more than flat
      EXPECT_GT(p.z_max - p.z_min, 0.3);
    }
}

TEST(Patches, RoofOfTwoPlanesSplitsAtTheRidge) {
  const double t = std::tan(15.0 * M_PI / 180.0);
  const TriangleMesh roof = test::height_field_solid(
      [&](double x, double) { return 5 + t * (10 - std::abs(x - 10)); }, 0, 20, 0, 30, 8, 6);
  auto a = analyze(roof, {}, {});
  ASSERT_TRUE(a);
  EXPECT_EQ(nonplanar_patches(roof), 2u);
  EXPECT_EQ(a->crease_edges, 6u);  // the ridge runs across 6 grid cells
  for (const Patch& p : a->patches)
    if (p.needs_nonplanar()) {
      EXPECT_NEAR(p.max_slope_deg, 15.0, 1e-9);
    }
  // With a crease angle wider than the 30° fold, the roof stays one patch.
  AnalysisParams wide;
  wide.crease_angle_deg = 35;
  EXPECT_EQ(nonplanar_patches(roof, wide), 1u);
}

TEST(Patches, RampIsOnePatch) {
  const double t = std::tan(20.0 * M_PI / 180.0);
  const TriangleMesh ramp =
      test::height_field_solid([&](double x, double) { return 2 + t * x; }, 0, 20, 0, 10, 10, 5);
  auto a = analyze(ramp, {}, {});
  ASSERT_TRUE(a);
  ASSERT_EQ(nonplanar_patches(ramp), 1u);
  const Patch& p = a->patches.front();
  EXPECT_NEAR(p.area, 200.0 / std::cos(20.0 * M_PI / 180.0), 1e-6);
  EXPECT_NEAR(p.z_max - p.z_min, 20 * t, 1e-9);
  EXPECT_NEAR(p.max_slope_deg, 20.0, 1e-9);
  EXPECT_EQ(p.faces.size(), 100u);
}

TEST(Patches, PlateauWithTwoGaussianBumpsIsOnePatch) {
  auto f = [](double x, double y) {
    auto bump = [&](double cx, double cy) {
      return 3.0 * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * 7.0 * 7.0));
    };
    return 10 + bump(25, 30) + bump(55, 30);
  };
  const TriangleMesh m = test::height_field_solid(f, 0, 80, 0, 60, 80, 60);
  auto a = analyze(m, {}, {});
  ASSERT_TRUE(a);
  EXPECT_EQ(nonplanar_patches(m), 1u);
  EXPECT_EQ(a->discontinuous_faces, 0u);
  EXPECT_EQ(a->crease_edges, 0u);
  EXPECT_EQ(a->patches.front().faces.size(), 2u * 80 * 60);  // the whole top
}

TEST(Patches, TinyAndFlatPatchesAreClassified) {
  TriangleMesh m = test::box({0, 0, 0}, {1, 1, 1});  // 1 mm² flat top
  test::append(m, test::height_field_solid([](double x, double) { return 2 + 0.3 * x; }, 5, 6, 0, 1,
                                           2, 2));      // 1 mm² sloped
  test::append(m, test::box({10, 0, 0}, {30, 20, 4}));  // 400 mm² flat
  AnalysisParams p;
  auto a = analyze(m, p, {});
  ASSERT_TRUE(a);
  ASSERT_EQ(a->patches.size(), 3u);
  EXPECT_EQ(a->patches[0].verdict, PatchVerdict::flat);
  EXPECT_EQ(a->patches[1].verdict, PatchVerdict::too_small);
  EXPECT_EQ(a->patches[2].verdict, PatchVerdict::too_small);
  p.min_patch_area = 0.5;
  auto b = analyze(m, p, {});
  ASSERT_TRUE(b);
  std::size_t n = 0;
  for (const Patch& q : b->patches) n += q.needs_nonplanar();
  EXPECT_EQ(n, 1u);  // the sloped one; the unit cube's top is flat
}

}  // namespace
}  // namespace nonplanar
