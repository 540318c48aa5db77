#include <gtest/gtest.h>

#include <random>

#include "io/repair.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A triangle soup (3 vertices per face), as an STL gives it, with jitter below `noise`.
TriangleMesh soup(const TriangleMesh& m, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-noise, noise);
  TriangleMesh s;
  for (const auto& f : m.faces) {
    const int b = static_cast<int>(s.vertices.size());
    for (int v : f) s.vertices.push_back(m.vertices[v] + Vec3(d(rng), d(rng), d(rng)));
    s.faces.push_back({b, b + 1, b + 2});
  }
  return s;
}

TEST(Weld, MergesNearCoincidentVerticesOnly) {
  const TriangleMesh sphere = test::icosphere({3, -2, 1}, 10.0, 3);
  std::size_t collapsed = 99;
  const TriangleMesh w = io::weld(soup(sphere, 1e-5, 1), 1e-4, &collapsed);
  EXPECT_EQ(w.vertices.size(), sphere.vertices.size());
  EXPECT_EQ(w.faces.size(), sphere.faces.size());
  EXPECT_EQ(collapsed, 0u);
  EXPECT_EQ(build_topology(w).open_edges, 0u);
  // With a tolerance below the noise, nothing merges and every edge is open.
  const TriangleMesh none = io::weld(soup(sphere, 1e-5, 1), 1e-9, nullptr);
  EXPECT_EQ(none.vertices.size(), 3 * sphere.faces.size());
}

TEST(Weld, DropsCollapsedFacesAndUnusedVertices) {
  TriangleMesh m = test::box({0, 0, 0}, {1, 1, 1});
  m.vertices.emplace_back(0.5, 0.5, 1.0);
  m.vertices.emplace_back(0.5, 0.5, 1.0 + 1e-9);  // same point within tolerance
  m.vertices.emplace_back(7, 7, 7);               // never used
  const int a = static_cast<int>(m.vertices.size()) - 3;
  m.faces.push_back({a, a + 1, 0});  // collapses to an edge
  std::size_t collapsed = 0;
  const TriangleMesh w = io::weld(m, 1e-6, &collapsed);
  EXPECT_EQ(collapsed, 1u);
  EXPECT_EQ(w.faces.size(), 12u);
  EXPECT_EQ(w.vertices.size(), 8u);
}

TEST(Orientation, FixesFlippedFacesAndInvertedShells) {
  TriangleMesh m = test::icosphere({0, 0, 0}, 5.0, 2);
  const double v = signed_volume(m);
  ASSERT_GT(v, 0);
  for (std::size_t f = 0; f < m.faces.size(); f += 3) std::swap(m.faces[f][1], m.faces[f][2]);
  bool inverted = true;
  TriangleMesh fixed = m;
  const std::size_t flips = io::orient_outward(fixed, build_topology(fixed), &inverted);
  EXPECT_EQ(flips, (m.faces.size() + 2) / 3);
  EXPECT_FALSE(inverted);
  EXPECT_NEAR(signed_volume(fixed), v, 1e-9);
  EXPECT_EQ(build_topology(fixed).inconsistent_edges, 0u);

  TriangleMesh inside_out = test::icosphere({0, 0, 0}, 5.0, 2);
  for (auto& f : inside_out.faces) std::swap(f[1], f[2]);
  EXPECT_EQ(io::orient_outward(inside_out, build_topology(inside_out), &inverted),
            inside_out.faces.size());
  EXPECT_TRUE(inverted);
  EXPECT_NEAR(signed_volume(inside_out), v, 1e-9);
}

TEST(Orientation, KeepsACavityPointingInward) {
  TriangleMesh m = test::box({0, 0, 0}, {10, 10, 10});
  TriangleMesh cavity = test::box({3, 3, 3}, {6, 6, 6});
  for (auto& f : cavity.faces) std::swap(f[1], f[2]);
  test::append(m, cavity);
  bool inverted = true;
  EXPECT_EQ(io::orient_outward(m, build_topology(m), &inverted), 0u);
  EXPECT_FALSE(inverted);
  EXPECT_NEAR(signed_volume(m), 1000.0 - 27.0, 1e-9);
}

TEST(Placement, ScaleRotateAndCentreOnTheBed) {
  const auto dir = test::temp_dir("placement");
  ASSERT_TRUE(write_stl(dir / "a.stl", test::box({-50, 3, 7}, {-40, 23, 37})));  // 10×20×30
  LoadParams p;
  p.scale = 2.0;
  p.rotate_x_deg = 90;  // y → z: the part lies 20×60×40
  p.bed_center = {100, 120};
  auto r = load_mesh(dir / "a.stl", p, {});
  ASSERT_TRUE(r) << r.error().message;
  const BoundingBox b = bounding_box(r->mesh);
  EXPECT_NEAR(b.size().x(), 20, 1e-6);
  EXPECT_NEAR(b.size().y(), 60, 1e-6);
  EXPECT_NEAR(b.size().z(), 40, 1e-6);
  EXPECT_NEAR(b.min.z(), 0, 1e-9);
  EXPECT_NEAR(0.5 * (b.min.x() + b.max.x()), 100, 1e-9);
  EXPECT_NEAR(0.5 * (b.min.y() + b.max.y()), 120, 1e-9);
  EXPECT_NEAR(signed_volume(r->mesh), 6000.0 * 8.0, 1e-3);
}

TEST(Placement, RejectsBadParameters) {
  const auto dir = test::temp_dir("placement_bad");
  ASSERT_TRUE(write_stl(dir / "a.stl", test::box({0, 0, 0}, {1, 1, 1})));
  LoadParams p;
  p.scale = -1;
  auto r = load_mesh(dir / "a.stl", p, {});
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().status, Status::invalid_argument);
  EXPECT_EQ(r.error().message.rfind("scale:", 0), 0u);
}

}  // namespace
}  // namespace nonplanar
