// Which extrusions of a layer can touch (reach_groups.hpp), and the top skins' low-to-high
// order within such groups (layer_passes.hpp): strokes are reordered only against strokes
// beyond the head's reach, and a group is printed whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "program/layer_passes.hpp"
#include "program/reach_groups.hpp"

namespace nonplanar::program {
namespace {

ReachBox box(double x0, double y0, double z0, double x1, double y1, double z1) {
  ReachBox b;
  b.extend(Vec3(x0, y0, z0)), b.extend(Vec3(x1, y1, z1));
  return b;
}

TEST(ReachGroups, BoxesFartherApartThanTheHeadReachesAreApart) {
  const Toolhead head;
  // A low run (0.5 mm span): near = 0.4 + 0.5 + 0.45 + 0.1 = 1.45 mm.
  std::vector<ReachBox> b = {box(0, 0, 1, 10, 0.4, 1.5), box(0, 1.8, 1, 10, 2.2, 1.2),
                             box(0, 3.0, 1, 10, 3.4, 1.2), box(20, 0, 1, 30, 1, 1.1)};
  std::vector<std::size_t> g = reach_groups(b, head);
  EXPECT_EQ(g, (std::vector<std::size_t>{0, 0, 0, 3}));  // 1.4 mm apart, then 10 mm
  b[2] = box(0, 3.7, 1, 10, 3.9, 1.2);                   // 1.5 mm from the second
  g = reach_groups(b, head);
  EXPECT_EQ(g, (std::vector<std::size_t>{0, 0, 2, 3}));
  // A run 5 mm tall: the block reaches 8 mm, and a box 8.5 mm from the first three and 1 mm
  // from the fourth joins them all.
  b.push_back(box(18.5, 0, 6, 19, 1, 6));
  g = reach_groups(b, head);
  EXPECT_EQ(g, (std::vector<std::size_t>{0, 0, 0, 0, 0}));
}

// The ring of a sloped annulus, strokes across it left and right of the hole: sorted by
// height alone they alternate sides; in groups each side prints whole, low to high.
TEST(LowToHigh, PrintsEachGroupWholeLowToHigh) {
  const Toolhead head;
  std::vector<StrokeHeights> s;
  for (int i = 0; i < 10; ++i)
    for (double x : {0.0, 30.0}) {
      StrokeHeights h;
      const double z = 1 + 0.05 * i + (x > 0 ? 0.01 : 0);
      h.mean = z, h.first = z + 0.01, h.last = z - 0.01;
      h.box = box(x, 0.45 * i, z - 0.01, x + 5, 0.45 * i, z + 0.01);
      s.push_back(h);
    }
  const LowToHigh r = low_to_high(s, head);
  ASSERT_EQ(r.order.size(), s.size());
  for (std::size_t k = 0; k < r.order.size(); ++k) {
    EXPECT_EQ(r.order[k], k < 10 ? 2 * k : 2 * (k - 10) + 1) << k;
    EXPECT_TRUE(r.reverse[r.order[k]]);  // from its low end
  }
}

// Against the plain rule (every stroke by mean height): two strokes change places only when
// they are farther apart than the head reaches at the run's span.
TEST(LowToHigh, ReordersOnlyStrokesBeyondTheHeadsReach) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> at(0, 60), len(0.5, 8), rise(0, 3);
  for (const double block : {8.0, 3.0}) {
    Toolhead head;
    head.block_radius = block;
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<StrokeHeights> s(40);
      double lo = 1e9, hi = -1e9;
      for (StrokeHeights& h : s) {
        const double x = at(rng), y = at(rng), z = 1 + rise(rng);
        h.mean = h.first = h.last = z;
        h.box = box(x, y, z, x + len(rng), y + 0.45, z);
        lo = std::min(lo, z), hi = std::max(hi, z);
      }
      const LowToHigh r = low_to_high(s, head);
      std::vector<std::size_t> place(s.size());
      for (std::size_t k = 0; k < r.order.size(); ++k) place[r.order[k]] = k;
      const double near = head.reach_under(hi - lo) + 0.45 + 0.1;
      for (std::size_t a = 0; a < s.size(); ++a)
        for (std::size_t b = 0; b < s.size(); ++b) {
          if (!(s[a].mean < s[b].mean) || place[a] < place[b]) continue;
          // b (higher) before a: their boxes lie apart.
          const ReachBox &A = s[a].box, &B = s[b].box;
          const double gap = std::max(
              {A.lo.x() - B.hi.x(), B.lo.x() - A.hi.x(), A.lo.y() - B.hi.y(), B.lo.y() - A.hi.y()});
          EXPECT_GT(gap, near) << trial << " " << a << " " << b;
        }
    }
  }
}

TEST(OrderReachGroups, NearestGroupFirstEachInItsOwnOrder) {
  auto path = [](double x0, double y, double x1) {
    ExtrusionPath p;
    p.points = {Vec3(x0, y, 1), Vec3(x1, y, 1)};
    p.height = {0.2, 0.2};
    return p;
  };
  // Three groups along x: A at 0-5, B at 20-25, C at 40-45; given interleaved.
  const std::vector<ExtrusionPath> ps = {path(0, 0, 5),    path(40, 0, 45),    path(20, 0, 25),
                                         path(5, 0.45, 0), path(45, 0.45, 40), path(25, 0.45, 20)};
  const Toolhead head;
  EXPECT_EQ(order_reach_groups(ps, head, Vec2(50, 0)),
            (std::vector<std::size_t>{1, 4, 2, 5, 0, 3}));  // C (nearest), then B, then A
  EXPECT_EQ(order_reach_groups(ps, head, Vec2(-5, 0)),
            (std::vector<std::size_t>{0, 3, 2, 5, 1, 4}));
}

}  // namespace
}  // namespace nonplanar::program
