// PrintedTop (src/program/printed_top.hpp): the highest material laid per 1 mm cell, its
// cells made where beads are laid when no bounds were given.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "program/printed_top.hpp"

namespace nonplanar::program {
namespace {

// Beads laid far apart (a skirt 100 mm from the part, then a purge line beyond the bed's
// origin) are all kept by a grid that grows for them, and it answers what one made over all
// of them at once on the same lattice (from (0, 0)) answers.
TEST(PrintedTop, GrowsForBeadsOffItsCellsAndKeepsTheLattice) {
  const std::vector<std::pair<Vec3, Vec3>> beads = {
      {{50.3, 50.7, 0.2}, {60.1, 50.7, 0.2}},     {{150.2, 140.9, 3.0}, {150.2, 160.4, 3.0}},
      {{-20.5, -3.2, 0.3}, {-10.0, -3.2, 0.3}},   {{55.0, 52.0, 7.5}, {55.5, 52.0, 7.5}},
      {{250.6, 20.2, 1.25}, {251.0, 20.2, 1.25}},
  };
  PrintedTop grown, fixed(Vec2(-40, -10), Vec2(260, 170));
  for (const auto& [a, b] : beads) grown.lay(a, b), fixed.lay(a, b);
  const double r = 1.2;
  for (double x = -30; x <= 255; x += 2.5)
    for (double y = -8; y <= 165; y += 2.5) {
      const Vec2 a(x, y), b(x + 3.1, y + 1.7);
      EXPECT_EQ(grown.over(a, b, r), fixed.over(a, b, r)) << x << " " << y;
    }
  // Each bead is found where it was laid, nothing where none was.
  EXPECT_DOUBLE_EQ(grown.over({150.2, 150}, {150.2, 150}, 0.5), 3.0);
  EXPECT_NEAR(grown.over({-15, -3.2}, {-15, -3.2}, 0.5), 0.3, 1e-7);  // (cells hold floats)
  EXPECT_DOUBLE_EQ(grown.over({251, 20}, {251, 20}, 0.5), 1.25);
  EXPECT_DOUBLE_EQ(grown.over({55.2, 52}, {55.2, 52}, 0.5), 7.5);
  EXPECT_EQ(grown.over({100, 100}, {100, 100}, 0.5), -std::numeric_limits<double>::infinity());
  // A travel over the tall bead clears it; one beside nothing keeps its own top.
  EXPECT_DOUBLE_EQ(grown.to_clear({40, 52, 1}, {70, 52, 1}, 1.0, 1.0), 7.5);
  EXPECT_DOUBLE_EQ(grown.to_clear({100, 100, 1}, {110, 100, 1}, 1.0, 1.0), 1.0);
}

// A point too far for any grid (past 4096 cells on a side) is not kept; the rest are.
TEST(PrintedTop, KeepsNoPointPastTheGridsLimit) {
  PrintedTop t;
  t.lay({10, 10, 1}, {11, 10, 1});
  t.lay({9000, 10, 5}, {9001, 10, 5});
  EXPECT_EQ(t.over({9000.5, 10}, {9000.5, 10}, 0.5), -std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(t.over({10.5, 10}, {10.5, 10}, 0.5), 1.0);
}

}  // namespace
}  // namespace nonplanar::program
