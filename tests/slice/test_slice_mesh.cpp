#include <gtest/gtest.h>

#include <cmath>

#include "nonplanar/slice.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

TEST(SliceMesh, VerticesExactlyOnTheCuttingPlane) {
  // Two boxes meet at z = 0.1, which is exactly the first cutting height (h₁ = 0.2): every
  // vertex of the joint lies on the plane, and two faces lie in it. A vertex on the plane
  // counts as above, so the cut still yields the one 10 × 10 outline.
  TriangleMesh m = test::box({0, 0, 0}, {10, 10, 0.1});
  test::append(m, test::box({0, 0, 0.1}, {10, 10, 0.4}));
  auto layers = slice_mesh(m, {}, {});
  ASSERT_TRUE(layers);
  ASSERT_EQ(layers->size(), 2u);
  EXPECT_DOUBLE_EQ((*layers)[0].z_slice, 0.1);
  for (const SlicedLayer& l : *layers) {
    ASSERT_EQ(l.islands.size(), 1u) << l.z_slice;
    EXPECT_NEAR(area(l.islands), 100.0, 1e-6) << l.z_slice;
  }
}

TEST(SliceMesh, OverlappingShellsAreUnited) {
  TriangleMesh m = test::box({0, 0, 0}, {10, 10, 2});
  test::append(m, test::box({5, 5, 0}, {15, 15, 2}));  // overlaps a 5 × 5 square
  auto layers = slice_mesh(m, {}, {});
  ASSERT_TRUE(layers);
  for (const SlicedLayer& l : *layers) {
    ASSERT_EQ(l.islands.size(), 1u);
    EXPECT_NEAR(area(l.islands), 100 + 100 - 25, 1e-6);
  }
}

TEST(SliceMesh, SmallGapsInAnOpenMeshAreClosed) {
  // Walls made of 0.5 mm wide quads; drop one wall triangle: every cut through it leaves an
  // open chain with a gap under 0.5 mm, closed by joining the chain's ends.
  TriangleMesh m =
      test::height_field_solid([](double, double) { return 2.0; }, 0, 10, 0, 10, 20, 20);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    const Vec3& a = m.vertices[m.faces[f][0]];
    const Vec3& b = m.vertices[m.faces[f][1]];
    const Vec3& c = m.vertices[m.faces[f][2]];
    if (a.x() == 0 && b.x() == 0 && c.x() == 0) {
      m.faces.erase(m.faces.begin() + static_cast<long>(f));
      break;
    }
  }
  auto layers = slice_mesh(m, {}, {});
  ASSERT_TRUE(layers);
  for (const SlicedLayer& l : *layers) EXPECT_NEAR(area(l.islands), 100.0, 1e-6);
}

}  // namespace
}  // namespace nonplanar
