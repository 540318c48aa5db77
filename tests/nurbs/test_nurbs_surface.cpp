#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "nonplanar/nurbs.hpp"

namespace nonplanar {
namespace {

NurbsSurface bilinear(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  NurbsSurface s;
  s.p = s.q = 1;
  s.n_u = s.n_v = 2;
  s.U = s.V = {0, 0, 1, 1};
  s.points = {a, b, c, d};  // (0,0) (0,1) (1,0) (1,1)
  s.weights = {1, 1, 1, 1};
  return s;
}

TEST(NurbsSurface, BilinearPatchIsExact) {
  const Vec3 a(0, 0, 1), b(0, 2, 3), c(4, 0, -1), d(5, 3, 2);
  const NurbsSurface s = bilinear(a, b, c, d);
  ASSERT_TRUE(s.valid());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U01(0, 1);
  for (int k = 0; k < 200; ++k) {
    const double u = U01(rng), v = U01(rng);
    const Vec3 expect = (1 - u) * (1 - v) * a + (1 - u) * v * b + u * (1 - v) * c + u * v * d;
    EXPECT_LT((s.evaluate(u, v) - expect).norm(), 1e-12);
    const auto D = s.derivatives(u, v, 2);
    EXPECT_LT((D[1][0] - ((1 - v) * (c - a) + v * (d - b))).norm(), 1e-12);
    EXPECT_LT((D[1][1] - (a - b - c + d)).norm(), 1e-12);
    EXPECT_LT(D[2][0].norm(), 1e-12);
  }
}

// Quarter cylinder: a rational quadratic quarter circle of radius r in u, a line in v.
NurbsSurface quarter_cylinder(double r, double h) {
  NurbsSurface s;
  s.p = 2;
  s.q = 1;
  s.n_u = 3;
  s.n_v = 2;
  s.U = {0, 0, 0, 1, 1, 1};
  s.V = {0, 0, 1, 1};
  const double w = std::sqrt(0.5);
  s.points = {{r, 0, 0}, {r, 0, h}, {r, r, 0}, {r, r, h}, {0, r, 0}, {0, r, h}};
  s.weights = {1, 1, w, w, 1, 1};
  return s;
}

TEST(NurbsSurface, RationalQuarterCylinderIsAnExactCircle) {
  const double r = 7.5, h = 3.0;
  const NurbsSurface s = quarter_cylinder(r, h);
  ASSERT_TRUE(s.valid());
  for (int i = 0; i <= 50; ++i)
    for (int j = 0; j <= 4; ++j) {
      const double u = i / 50.0, v = j / 4.0;
      const Vec3 p = s.evaluate(u, v);
      EXPECT_NEAR(p.head<2>().norm(), r, 1e-12);
      EXPECT_NEAR(p.z(), v * h, 1e-12);
      // The normal of a cylinder is radial and horizontal.
      const Vec3 n = s.normal(u, v);
      EXPECT_NEAR(std::abs(n.head<2>().dot(p.head<2>() / r)), 1.0, 1e-12);
      EXPECT_NEAR(n.z(), 0.0, 1e-12);
    }
  EXPECT_LT((s.evaluate(0.5, 0) - Vec3(r * std::sqrt(0.5), r * std::sqrt(0.5), 0)).norm(), 1e-12);
}

NurbsSurface random_rational(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-1, 1), w(0.5, 2.0);
  NurbsSurface s;
  s.p = 3;
  s.q = 2;
  s.U = {0, 0, 0, 0, 0.3, 0.55, 1, 1, 1, 1};
  s.V = {0, 0, 0, 0.4, 1, 1, 1};
  s.n_u = 6;
  s.n_v = 4;
  for (int i = 0; i < s.n_u * s.n_v; ++i) {
    s.points.emplace_back(i / s.n_v + 0.3 * d(rng), i % s.n_v + 0.3 * d(rng), d(rng));
    s.weights.push_back(w(rng));
  }
  return s;
}

TEST(NurbsSurface, DerivativesMatchFiniteDifferences) {
  const NurbsSurface s = random_rational(11);
  ASSERT_TRUE(s.valid());
  const double h = 1e-5;
  for (double u : {0.1, 0.42, 0.77}) {
    for (double v : {0.15, 0.5, 0.93}) {
      const auto D = s.derivatives(u, v, 2);
      EXPECT_LT((D[0][0] - s.evaluate(u, v)).norm(), 1e-12);
      const Vec3 su = (s.evaluate(u + h, v) - s.evaluate(u - h, v)) / (2 * h);
      const Vec3 sv = (s.evaluate(u, v + h) - s.evaluate(u, v - h)) / (2 * h);
      EXPECT_LT((D[1][0] - su).norm(), 1e-6 * (1 + su.norm()));
      EXPECT_LT((D[0][1] - sv).norm(), 1e-6 * (1 + sv.norm()));
      const auto Dp = s.derivatives(u + h, v, 1), Dm = s.derivatives(u - h, v, 1);
      const auto Dq = s.derivatives(u, v + h, 1), Dr = s.derivatives(u, v - h, 1);
      EXPECT_LT((D[2][0] - (Dp[1][0] - Dm[1][0]) / (2 * h)).norm(), 1e-5 * (1 + D[2][0].norm()));
      EXPECT_LT((D[1][1] - (Dq[1][0] - Dr[1][0]) / (2 * h)).norm(), 1e-5 * (1 + D[1][1].norm()));
      EXPECT_LT((D[0][2] - (Dq[0][1] - Dr[0][1]) / (2 * h)).norm(), 1e-5 * (1 + D[0][2].norm()));
      const Vec3 n = s.normal(u, v);
      EXPECT_NEAR(n.norm(), 1.0, 1e-12);
      EXPECT_NEAR(n.dot(D[1][0]), 0.0, 1e-10);
    }
  }
}

TEST(NurbsSurface, KnotInsertionKeepsTheShape) {
  const NurbsSurface s = random_rational(5);
  NurbsSurface t = s;
  t.insert_knot_u(0.3);  // raises an existing knot's multiplicity
  t.insert_knot_u(0.8, 2);
  t.insert_knot_v(0.25);
  ASSERT_TRUE(t.valid());
  EXPECT_EQ(t.n_u, s.n_u + 3);
  EXPECT_EQ(t.n_v, s.n_v + 1);
  double worst = 0;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j)
      worst =
          std::max(worst, (t.evaluate(i / 40.0, j / 40.0) - s.evaluate(i / 40.0, j / 40.0)).norm());
  EXPECT_LT(worst, 1e-12);
}

TEST(NurbsSurface, ValidRejectsBrokenSurfaces) {
  NurbsSurface s = random_rational(1);
  s.weights[3] = 0;
  EXPECT_FALSE(s.valid());
  s = random_rational(1);
  s.U[5] = 0.1;  // decreasing
  EXPECT_FALSE(s.valid());
  s = random_rational(1);
  s.points.pop_back();
  EXPECT_FALSE(s.valid());
}

}  // namespace
}  // namespace nonplanar
