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

// The mapped mesh lies within the tolerance of the exact map, measured as a distance: the map
// moves points in z only, so a point of a face's preimage maps dz off the face and dz·|n_z| from
// its plane. Sampled at the edges' midpoints (what the rounds test) and the faces' centroids,
// over the bump's curved band.
TEST(NormalizeMesh, TheMappedMeshLiesWithinTheToleranceOfTheExactMap) {
  const TriangleMesh sphere = test::icosphere(Vec3(0, 0, 8), 9, 2);
  const layers::ShellPlan plan = bump_plan();
  const layers::ShellField field(plan);
  const NormalizeParams params;
  auto n = normalize_mesh(sphere, field, params, {});
  ASSERT_TRUE(n);
  auto image = [&](const Vec3& p) {
    return Vec3(p.x(), p.y(), field.zeta(field.T(p.x(), p.y(), p.z())));
  };
  auto preimage = [&](const Vec3& q) {
    return Vec3(q.x(), q.y(), field.z_at(q.x(), q.y(), field.t_of_zeta(q.z())));
  };
  double at_edges = 0, inside = 0;
  for (const auto& f : n->mesh.faces) {
    const Vec3 A = n->mesh.vertices[f[0]], B = n->mesh.vertices[f[1]], C = n->mesh.vertices[f[2]];
    const Vec3 nrm = (B - A).cross(C - A).normalized();
    const Vec3 a = preimage(A), b = preimage(B), c = preimage(C);
    const Vec3 probes[4] = {0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), (a + b + c) / 3.0};
    for (int k = 0; k < 4; ++k) {
      double& worst = k < 3 ? at_edges : inside;
      worst = std::max(worst, std::abs((image(probes[k]) - A).dot(nrm)));
    }
  }
  // The rounds test the edges (both faces' planes); a face's inside is not tested, and on this
  // bump's raster (bilinear between 0.1 mm nodes) it strays a little farther.
  EXPECT_LE(at_edges, params.tolerance + 1e-9);
  EXPECT_LE(inside, 1.2 * params.tolerance);
  EXPECT_GT(at_edges, 0.5 * params.tolerance);  // split no further than it needs
}

// A wall keeps its faces through the band: its image stays in its vertical plane (n_z = 0),
// so the map's error in z moves none of its sections. A box 12 mm wide through the bump's
// band, its walls in faces of 1.5 mm sides (diagonals 2.1 mm, long enough to be probed).
TEST(NormalizeMesh, AWallKeepsItsFaces) {
  const TriangleMesh box = test::subdivide(test::box(Vec3(-6, -6, 0), Vec3(6, 6, 16)), 3);
  const layers::ShellPlan plan = bump_plan();
  const layers::ShellField field(plan);
  auto n = normalize_mesh(box, field, {}, {});
  ASSERT_TRUE(n);
  auto walls = [](const TriangleMesh& m) {
    std::size_t count = 0;
    for (const auto& f : m.faces) {
      const Vec3 nrm =
          (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]);
      count += std::abs(nrm.z()) < 1e-9 * nrm.norm();
    }
    return count;
  };
  const std::size_t before = walls(box), after = walls(n->mesh);
  ASSERT_EQ(before, 4u * 2 * 64);
  // 1408 when a wall was split for its error in z as a flat face is, 1024 when every edge over
  // 2 mm in the band was split regardless.
  EXPECT_EQ(after, before);
  // Its flat faces are split where the map bends them (768 faces -> 1600).
  EXPECT_GT(n->mesh.faces.size(), box.faces.size());
}

}  // namespace
}  // namespace nonplanar
