#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "analysis/curvature.hpp"
#include "nonplanar/analysis.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

using analysis::angle_deficit;
using analysis::face_geometry;

double total_deficit(const TriangleMesh& m, const std::vector<char>* mask = nullptr) {
  const auto c = angle_deficit(m, build_topology(m), face_geometry(m), mask);
  return std::accumulate(c.deficit.begin(), c.deficit.end(), 0.0);
}

TEST(Curvature, GaussBonnetOnClosedGenusZeroMeshes) {
  EXPECT_NEAR(total_deficit(test::icosphere({1, 2, 3}, 7.0, 3)), 4 * M_PI, 1e-6);
  EXPECT_NEAR(total_deficit(test::box({0, 0, 0}, {3, 4, 5})), 4 * M_PI, 1e-6);
  const TriangleMesh bumpy = test::height_field_solid(
      [](double x, double y) { return 5 + std::sin(x) * std::cos(y); }, 0, 10, 0, 10, 30, 30);
  EXPECT_NEAR(total_deficit(bumpy), 4 * M_PI, 1e-6);
}

TEST(Curvature, BoundaryVerticesUseHalfTurn) {
  // The top of a bumpy block alone is a disk (Euler characteristic 1): interior deficits
  // plus boundary turning (π − Θ) sum to 2π.
  const TriangleMesh m = test::height_field_solid(
      [](double x, double y) { return 5 + 0.3 * std::sin(x) * std::cos(y); }, 0, 6, 0, 4, 12, 8);
  std::vector<char> top(m.faces.size(), 0);
  for (std::size_t f = 0; f < 2 * 12 * 8; f += 4) top[f] = top[f + 1] = 1;  // top faces
  EXPECT_NEAR(total_deficit(m, &top), 2 * M_PI, 1e-6);
}

TEST(Curvature, NormalisedCurvatureOfASphereIsOneOverRSquared) {
  const double r = 12.0;
  const TriangleMesh s = test::icosphere({0, 0, 0}, r, 4);  // 5120 faces
  const auto c = angle_deficit(s, build_topology(s), face_geometry(s), nullptr);
  std::vector<double> k = c.normalized();
  std::sort(k.begin(), k.end());
  const double expected = 1.0 / (r * r);
  EXPECT_NEAR(k[k.size() / 2], expected, 0.01 * expected);  // median within 1 %
  EXPECT_NEAR(k.front(), expected, 0.25 * expected);        // every vertex within 25 %
  EXPECT_NEAR(k.back(), expected, 0.25 * expected);
}

TEST(Curvature, ConeApexIsDiscontinuous) {
  // A shallow cone (15°) on a block: only the apex carries curvature, all of it.
  const double t = std::tan(15.0 * M_PI / 180.0);
  const TriangleMesh m = test::height_field_solid(
      [&](double x, double y) { return 10 - t * std::hypot(x, y); }, -10, 10, -10, 10, 20, 20);
  const auto topo = build_topology(m);
  const auto geom = face_geometry(m);
  std::vector<char> mask(m.faces.size(), 0);
  for (std::size_t f = 0; f < m.faces.size(); ++f) mask[f] = geom.normals[f].z() > 0.5;
  const auto c = angle_deficit(m, topo, geom, &mask);
  const auto disc =
      analysis::discontinuous_vertices(m, c, mask, AnalysisParams{}.tau, AnalysisParams{}.epsilon);
  const int apex = 10 * 21 + 10;  // grid vertex at (0, 0)
  EXPECT_NEAR(m.vertices[apex].z(), 10.0, 1e-12);
  EXPECT_TRUE(disc[apex]);
  EXPECT_GT(c.deficit[apex], 0.05);
  // Nothing away from the apex is flagged: the flanks are developable.
  for (std::size_t v = 0; v < disc.size(); ++v)
    if (disc[v]) {
      EXPECT_LT(m.vertices[v].head<2>().norm(), 1.5) << "vertex " << v;
    }
}

}  // namespace
}  // namespace nonplanar
