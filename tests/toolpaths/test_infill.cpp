// Solid infill lines fitted to each island (src/toolpaths/infill.cpp): a side along the lines
// gets a line beside it, and the lines' spacing stays within 20 % of the bead's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar {
namespace {

constexpr double kS = 0.407;  // a 0.45 mm bead's spacing on a 0.2 mm layer

ExPolygon rect(double x0, double y0, double x1, double y1) {
  return {{{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}, {}};
}

// The lines' heights (y) across a region along x, sorted.
std::vector<double> heights(const std::vector<paths::InfillLine>& lines) {
  std::vector<double> y;
  for (const auto& l : lines) y.push_back(l.line.front().y());
  std::sort(y.begin(), y.end());
  return y;
}

TEST(Infill, FittedLinesReachBothSidesAlongThem) {
  // 10.13 mm across, 9.713 mm between the outermost lines' centres (s / 2 and 5 µm in): 24
  // intervals of 0.4047 mm.
  for (double y0 : {0.0, 0.3, 0.17}) {
    SCOPED_TRACE(y0);
    const auto lines = paths::infill_lines({rect(0, y0, 20, y0 + 10.13)}, 0, kS, kS, true);
    const std::vector<double> y = heights(lines);
    ASSERT_EQ(y.size(), 25u);
    EXPECT_NEAR(y.front() - y0, 0.5 * kS, 0.01);
    EXPECT_NEAR(y0 + 10.13 - y.back(), 0.5 * kS, 0.01);
    for (std::size_t k = 1; k < y.size(); ++k) EXPECT_NEAR(y[k] - y[k - 1], 9.713 / 24, 1e-6);
    for (const auto& l : lines) {
      EXPECT_NEAR(l.spacing, 9.713 / 24, 1e-6);
      // Ends back at the region's edge (the bead's centre line runs its whole length).
      EXPECT_NEAR(std::min(l.line.front().x(), l.line.back().x()), 0, 1e-3);
      EXPECT_NEAR(std::max(l.line.front().x(), l.line.back().x()), 20, 1e-3);
    }
  }
  // On the global grid a side may get its first line up to a spacing further in.
  const std::vector<double> grid =
      heights(paths::infill_lines({rect(0, 0.3, 20, 10.43)}, 0, kS, kS));
  EXPECT_GT(grid.front() - 0.3, 0.5 * kS + 0.1);
}

TEST(Infill, EachIslandGetsItsOwnSpacingWithinLimits) {
  // Two islands 4.0 and 2.2 mm across; a strip 0.6 mm across takes one line in its middle.
  const auto lines = paths::infill_lines(
      {rect(0, 0, 10, 4.0), rect(20, 0, 30, 2.2), rect(40, 0, 50, 0.6)}, 0, kS, kS, true);
  double wide = 0, narrow = 0;
  int strip = 0;
  for (const auto& l : lines) {
    EXPECT_GE(l.spacing, 0.8 * kS - 1e-9);
    EXPECT_LE(l.spacing, 1.2 * kS + 1e-9);
    const double x = l.line.front().x();
    if (x < 15) {
      wide = l.spacing;
    } else if (x < 35) {
      narrow = l.spacing;
    } else {
      ++strip;
      EXPECT_NEAR(l.line.front().y(), 0.3, 1e-6);
    }
  }
  EXPECT_NEAR(wide, (4.0 - kS - 0.01) / 9, 1e-6);    // 3.583 mm: 9 intervals
  EXPECT_NEAR(narrow, (2.2 - kS - 0.01) / 4, 1e-6);  // 1.783 mm: 4 intervals
  EXPECT_EQ(strip, 1);
}

}  // namespace
}  // namespace nonplanar
