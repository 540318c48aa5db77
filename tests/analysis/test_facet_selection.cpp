#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>

#include "nonplanar/analysis.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// Independent count straight from the binary STL bytes: normal from the winding of the raw
// floats, painted when its z component exceeds cos 30°.
std::size_t raw_painted_count(const std::string& bytes) {
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  std::size_t count = 0;
  for (std::uint32_t t = 0; t < n; ++t) {
    float f[9];
    std::memcpy(f, bytes.data() + 84 + 50 * static_cast<std::size_t>(t) + 12, sizeof f);
    const double ux = f[3] - f[0], uy = f[4] - f[1], uz = f[5] - f[2];
    const double vx = f[6] - f[0], vy = f[7] - f[1], vz = f[8] - f[2];
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (len > 0 && nz / len > std::cos(30.0 * M_PI / 180.0)) ++count;
  }
  return count;
}

TEST(FacetSelection, WingPaintedCountMatchesIndependentCount) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  const auto file = dir / "np_curvislicer_wing.stl";
  const std::size_t expected = raw_painted_count(test::read_bytes(file));
  auto m = load_mesh(file, {}, {});
  ASSERT_TRUE(m);
  auto a = analyze(m->mesh, {}, {});
  ASSERT_TRUE(a);
  EXPECT_EQ(a->painted_faces, expected);
  EXPECT_EQ(expected, 82u);
}

TEST(FacetSelection, ThresholdFollowsMaxAngle) {
  // A ramp rising at 20°: painted at max_angle 30, not at 15.
  const double t = std::tan(20.0 * M_PI / 180.0);
  const TriangleMesh ramp =
      test::height_field_solid([&](double x, double) { return 1 + t * x; }, 0, 10, 0, 10, 4, 4);
  AnalysisParams p;
  auto a = analyze(ramp, p, {});
  ASSERT_TRUE(a);
  EXPECT_EQ(a->painted_faces, 32u);  // the 4×4×2 top faces; bottom and walls never
  p.max_angle_deg = 15;
  auto b = analyze(ramp, p, {});
  ASSERT_TRUE(b);
  EXPECT_EQ(b->painted_faces, 0u);
}

TEST(FacetSelection, BadParametersNameTheKey) {
  const TriangleMesh cube = test::box({0, 0, 0}, {1, 1, 1});
  AnalysisParams p;
  p.max_angle_deg = 90;
  auto a = analyze(cube, p, {});
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().status, Status::invalid_argument);
  EXPECT_EQ(a.error().message.rfind("max_angle:", 0), 0u);
  p = {};
  p.tau = std::nan("");
  EXPECT_EQ(analyze(cube, p, {}).error().message.rfind("tau:", 0), 0u);
}

TEST(FacetSelection, CancelFlagStopsTheStage) {
  std::atomic<bool> stop{true};
  Context ctx;
  ctx.cancel_flag = &stop;
  auto a = analyze(test::icosphere({0, 0, 0}, 1, 2), {}, ctx);
  ASSERT_FALSE(a);
  EXPECT_EQ(a.error().status, Status::cancelled);
}

}  // namespace
}  // namespace nonplanar
