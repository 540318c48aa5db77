// normalize_mesh (include/nonplanar/deform.hpp): the care box of a framed shell's map. Faces
// outside it are mapped at their corners and never split, and the mesh stays conforming (every
// edge between exactly two faces), so the slicer finds no crack where the two kinds meet.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "layers/shell_plan.hpp"
#include "nonplanar/deform.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A shell plan whose top H is a bump over [-12, 12]² (only its field is used here).
layers::ShellPlan bump_plan() {
  layers::ShellPlan s;
  s.N = 4, s.t = 0.2;
  s.top.origin = Vec2(-12, -12), s.top.cell = 0.1, s.top.nx = s.top.ny = 241;
  for (int i = 0; i < s.top.nx; ++i)
    for (int j = 0; j < s.top.ny; ++j) {
      const double x = -12 + 0.1 * i, y = -12 + 0.1 * j;
      s.top.h.push_back(10 + 2 * std::cos(0.2 * x) * std::cos(0.2 * y));
    }
  return s;
}

// How many faces hold each edge.
std::map<std::pair<int, int>, int> edge_uses(const TriangleMesh& m) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  return uses;
}

TEST(NormalizeMesh, FacesOutsideTheCareBoxStayWholeAndTheMeshConforms) {
  const TriangleMesh sphere = test::icosphere(Vec3(0, 0, 8), 9, 2);  // 320 faces
  const layers::ShellPlan plan = bump_plan();
  const layers::ShellField field(plan);
  NormalizeParams all;
  auto whole = normalize_mesh(sphere, field, all, {});
  ASSERT_TRUE(whole);
  NormalizeParams half = all;
  half.care_min = Vec2(-20, -20), half.care_max = Vec2(-2, 20);  // x <= -2 only
  auto cared = normalize_mesh(sphere, field, half, {});
  ASSERT_TRUE(cared);
  // Split inside the box, less than everywhere.
  EXPECT_GT(cared->mesh.faces.size(), sphere.faces.size());
  EXPECT_LT(cared->mesh.faces.size(), whole->mesh.faces.size());
  // No new vertex on a face wholly past the box: every vertex added lies at x < 0 (a face
  // reaching x <= -2 spans at most one of the icosphere's edges, under 3.5 mm, to the right).
  for (std::size_t v = sphere.vertices.size(); v < cared->mesh.vertices.size(); ++v)
    EXPECT_LT(cared->mesh.vertices[v].x(), 1.5);
  // Closed and conforming: each edge between two faces.
  for (const auto& [edge, n] : edge_uses(cared->mesh)) EXPECT_EQ(n, 2);
  for (const auto& [edge, n] : edge_uses(whole->mesh)) EXPECT_EQ(n, 2);
}

// The face limit is checked before a round is built, on the count the round would leave: a
// limit of exactly the result's size passes, one face fewer is refused.
TEST(NormalizeMesh, TheFaceLimitIsTheCountTheRoundsWouldLeave) {
  const TriangleMesh sphere = test::icosphere(Vec3(0, 0, 8), 9, 2);
  const layers::ShellPlan plan = bump_plan();  // the field keeps a reference to it
  const layers::ShellField field(plan);
  auto whole = normalize_mesh(sphere, field, {}, {});
  ASSERT_TRUE(whole);
  ASSERT_GT(whole->rounds, 1);
  NormalizeParams exact;
  exact.max_faces = whole->mesh.faces.size();
  auto fits = normalize_mesh(sphere, field, exact, {});
  ASSERT_TRUE(fits) << fits.error().message;
  EXPECT_EQ(fits->mesh.faces, whole->mesh.faces);
  NormalizeParams fewer = exact;
  --fewer.max_faces;
  auto refused = normalize_mesh(sphere, field, fewer, {});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().status, Status::unsupported);
  EXPECT_NE(refused.error().message.find("more than"), std::string::npos);
}

}  // namespace
}  // namespace nonplanar
