// The heights a shell beside taller material is printed at (src/layers/shell_levels.hpp): on a
// ramp whose points may wait a fixed slack, each level serves the points within that slack
// below it, so the share served grows with the number of levels.
#include <gtest/gtest.h>

#include <cmath>

#include "layers/shell_levels.hpp"

namespace nonplanar {
namespace {

struct Nodes {
  std::vector<double> u, lo, hi;
};

// n nodes evenly on u = 0 … 10 mm, each printable from u − 0.05 to u + slack.
Nodes ramp(int n, double slack) {
  Nodes r;
  for (int k = 0; k < n; ++k) {
    const double u = 10.0 * k / (n - 1);
    r.u.push_back(u), r.lo.push_back(u - 0.05), r.hi.push_back(u + slack);
  }
  return r;
}

// A level z serves the nodes with lo <= z <= hi: on the ramp with slack 0.5, u in
// [z − 0.5, z + 0.05], 0.55 mm of the 10 mm (5.5 %).
TEST(ShellLevels, OneLevelServesOneSlackOfARamp) {
  const Nodes r = ramp(10001, 0.5);
  const layers::LevelChoice c = layers::choose_levels(r.u, r.lo, r.hi, 1);
  ASSERT_EQ(c.levels.z.size(), 1u);
  EXPECT_NEAR(1 - c.banded, 0.055, 0.004);
}

TEST(ShellLevels, EachLevelServesAnotherSlackAndNoneComesEarly) {
  const Nodes r = ramp(10001, 0.5);
  const layers::LevelChoice c = layers::choose_levels(r.u, r.lo, r.hi, 8);
  ASSERT_EQ(c.levels.z.size(), 8u);  // each level adds 5.5 %: none is within 2 % of the best
  EXPECT_NEAR(1 - c.banded, 8 * 0.055, 0.02);
  for (std::size_t l = 1; l < c.levels.z.size(); ++l) {
    EXPECT_LE(c.levels.z[l - 1], c.levels.z[l]);
    EXPECT_LT(c.levels.last[l - 1], c.levels.last[l]);
  }
  EXPECT_DOUBLE_EQ(c.levels.at(-5), c.levels.z.front());  // past the ends: the end's level
  EXPECT_DOUBLE_EQ(c.levels.at(50), c.levels.z.back());
  // g is what the share says, and never earlier than a node may be printed.
  int served = 0;
  for (std::size_t k = 0; k < r.u.size(); ++k) {
    const double g = c.levels.at(r.u[k]);
    EXPECT_GE(g, r.lo[k] - 1e-12) << r.u[k];
    served += g <= r.hi[k];
  }
  EXPECT_NEAR(served / static_cast<double>(r.u.size()), 1 - c.banded, 1e-9);
}

// A level top (every node at 5 mm) takes one level and prints nothing in bands; a top with
// slack enough for the whole ramp, too.
TEST(ShellLevels, ALevelTopOrAmpleSlackTakesOneLevel) {
  const layers::LevelChoice flat =
      layers::choose_levels({5, 5, 5, 5}, {4.95, 4.95, 4.95, 4.95}, {5.5, 5.5, 5.5, 5.5}, 8);
  EXPECT_EQ(flat.levels.z.size(), 1u);
  EXPECT_DOUBLE_EQ(flat.banded, 0);
  const Nodes r = ramp(1001, 11);
  const layers::LevelChoice ample = layers::choose_levels(r.u, r.lo, r.hi, 8);
  EXPECT_EQ(ample.levels.z.size(), 1u);
  EXPECT_DOUBLE_EQ(ample.banded, 0);
  EXPECT_NEAR(ample.levels.at(0), 9.95, 1e-9);  // the highest lo: nothing before its time
}

TEST(ShellLevels, NoNodesNoLevels) {
  const layers::LevelChoice c = layers::choose_levels({}, {}, {}, 8);
  EXPECT_TRUE(c.levels.empty());
  EXPECT_TRUE(std::isinf(c.levels.at(3)));
}

}  // namespace
}  // namespace nonplanar
