#include <gtest/gtest.h>

#include "core/mesh_topology.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

TEST(Topology, ClosedBoxHasEveryEdgeManifold) {
  const TriangleMesh m = test::box({0, 0, 0}, {1, 2, 3});
  const MeshTopology t = build_topology(m);
  EXPECT_EQ(t.open_edges, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.inconsistent_edges, 0u);
  for (int a : t.across) EXPECT_GE(a, 0);
  EXPECT_NEAR(signed_volume(m), 6.0, 1e-12);
}

TEST(Topology, RemovedFaceLeavesThreeOpenEdges) {
  TriangleMesh m = test::box({0, 0, 0}, {1, 1, 1});
  m.faces.pop_back();
  EXPECT_EQ(build_topology(m).open_edges, 3u);
}

TEST(Topology, FlippedFaceGivesThreeInconsistentEdges) {
  TriangleMesh m = test::icosphere({0, 0, 0}, 1.0, 1);
  std::swap(m.faces[7][1], m.faces[7][2]);
  EXPECT_EQ(build_topology(m).inconsistent_edges, 3u);
}

TEST(Topology, ThirdFaceOnAnEdgeIsNonManifold) {
  TriangleMesh m = test::box({0, 0, 0}, {1, 1, 1});
  m.faces.push_back({m.faces[0][0], m.faces[0][1], static_cast<int>(m.vertices.size())});
  m.vertices.emplace_back(5, 5, 5);
  const MeshTopology t = build_topology(m);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_EQ(t.open_edges, 2u);  // the fin's two other edges
}

TEST(Topology, ComponentsCountSeparateShells) {
  TriangleMesh m = test::box({0, 0, 0}, {1, 1, 1});
  test::append(m, test::box({3, 0, 0}, {4, 1, 1}));
  test::append(m, test::icosphere({10, 0, 0}, 1, 1));
  int n = 0;
  const auto comp = face_components(m, &n);
  EXPECT_EQ(n, 3);
  EXPECT_NE(comp.front(), comp.back());
}

}  // namespace
}  // namespace nonplanar
