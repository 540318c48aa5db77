// LayerGaps (check.hpp): thickness where a layer's lines cross the top of the material under
// them, on moves built by hand: the layer printed just before, a piece printed later over an
// earlier layer, a bead in between hiding a deeper line, sparse infill over its lattice, and
// a layer printed in pieces meeting itself.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "nonplanar/check.hpp"

namespace nonplanar {
namespace {

PrintMove line(int layer, const Vec3& a, const Vec3& b, const char* type = "Solid infill") {
  PrintMove m;
  m.from = a, m.to = b;
  m.filament = 0.03 * (b - a).norm(), m.extruding = true, m.layer = layer, m.type = type;
  return m;
}

struct Measured {
  double min = 0, max = 0;
  std::size_t crossings = 0;
  std::vector<CrossingGap> seen;
};

Measured measure(const std::vector<PrintMove>& moves) {
  Measured r;
  LayerGaps g([&](const CrossingGap& c) { return r.seen.push_back(c), true; });
  for (const PrintMove& m : moves) g.add(m);
  g.finish();
  r.min = g.min, r.max = g.max, r.crossings = g.crossings;
  return r;
}

TEST(LayerGaps, ACurvedLayerOverTheOneBeforeIsItsHeightWhereTheyCross) {
  // Layer 0 along x, z = 0.2 + 0.1 x; layer 1 along y over it, one line dipped: at x = 2.75
  // it runs 0.15 over layer 0, elsewhere 0.2.
  std::vector<PrintMove> moves;
  for (double y = 0; y <= 2; y += 0.5)
    for (double x = 0; x < 6; x += 1)
      moves.push_back(line(0, {x, y, 0.2 + 0.1 * x}, {x + 1, y, 0.3 + 0.1 * x}));
  for (double x = 0.25; x < 6; x += 0.5) {
    const double z = 0.4 + 0.1 * x - (x == 2.75 ? 0.05 : 0.0);
    moves.push_back(line(1, {x, -0.5, z}, {x, 2.5, z}));
  }
  const Measured m = measure(moves);
  EXPECT_EQ(m.crossings, 12u * 5u);
  EXPECT_NEAR(m.min, 0.15, 1e-12);
  EXPECT_NEAR(m.max, 0.2, 1e-12);
  for (const CrossingGap& c : m.seen) EXPECT_TRUE(c.curved);
}

TEST(LayerGaps, APiecePrintedLaterFindsTheLayerUnderIt) {
  // Layer 0 over region A, layer 1 over region B far away, then layer 2, a piece over A
  // (a shell's layer printed after a core's), 0.15 mm over layer 0.
  std::vector<PrintMove> moves;
  moves.push_back(line(0, {0, 0, 0.2}, {10, 0, 0.2}));
  moves.push_back(line(0, {0, 1, 0.2}, {10, 1, 0.2}));
  moves.push_back(line(1, {50, 0, 0.4}, {60, 0, 0.4}));
  moves.push_back(line(2, {5, -1, 0.34}, {5, 2, 0.37}));  // 0.35 at y = 0, 0.36 at y = 1
  const Measured m = measure(moves);
  ASSERT_EQ(m.crossings, 2u);
  EXPECT_NEAR(m.min, 0.15, 1e-9);
  // Not the layer printed just before: it counts for the thinnest only.
  EXPECT_EQ(m.max, 0);
}

TEST(LayerGaps, ABeadInBetweenHidesTheLineUnderIt) {
  // Layers 0 and 1 along x at the same y, 0.2 apart; layer 2 across both at y = 0: it lies
  // on layer 1 (0.2), not on layer 0 (0.4), which layer 1's bead covers.
  std::vector<PrintMove> moves;
  moves.push_back(line(0, {0, 0, 0.2}, {10, 0, 0.2}));
  moves.push_back(line(1, {0, 0.1, 0.4}, {10, 0.1, 0.4}));
  moves.push_back(line(1, {0, 5, 0.4}, {10, 5.01, 0.41}));  // curved: layer 1 is searched
  moves.push_back(line(2, {5, -1, 0.6}, {5, 1, 0.6}));
  const Measured m = measure(moves);
  ASSERT_EQ(m.crossings, 1u);
  EXPECT_NEAR(m.min, 0.2, 1e-9);
  EXPECT_NEAR(m.max, 0.2, 1e-9);
}

TEST(LayerGaps, SparseInfillOverItsLatticeCountsForTheThinnestOnly) {
  // Sparse lines 2 mm apart along x (layer 0) and along y at odd x (layer 1), then two short
  // curved pieces of layer 2: one over layer 1's line at (3, 4), 0.2 mm up, one where no line
  // of layer 1 is near, spanning 0.4 mm down to layer 0's line at (2, 2).
  std::vector<PrintMove> moves;
  const char* sparse = "Internal infill";
  for (double y = 0; y <= 10; y += 2) moves.push_back(line(0, {0, y, 0.2}, {10, y, 0.2}, sparse));
  for (double x = 1; x <= 9; x += 2) moves.push_back(line(1, {x, 0, 0.4}, {x, 10, 0.4}, sparse));
  moves.push_back(line(2, {2.8, 4.2, 0.6}, {3.2, 3.8, 0.6}, sparse));
  moves.push_back(line(2, {1.8, 1.8, 0.6}, {2.2, 2.2, 0.601}, sparse));
  const Measured m = measure(moves);
  bool spans_two = false;
  for (const CrossingGap& c : m.seen) spans_two |= std::abs(c.gap - 0.4005) < 1e-9 && c.spans;
  EXPECT_TRUE(spans_two);
  EXPECT_NEAR(m.min, 0.2, 1e-9);
  // Layer 1 over layer 0, two flat layers: 0.2; layer 2's crossings all span.
  EXPECT_NEAR(m.max, 0.2, 1e-9);
}

TEST(LayerGaps, APieceMeetingItsLayerAtTheSameHeightIsNoThickness) {
  // A sloped line of layer 0 continued in layer 2 (after a core layer elsewhere) by a piece
  // that starts where it ended, 1 µm higher and a little aside: one layer side by side.
  std::vector<PrintMove> moves;
  moves.push_back(line(0, {0, 0, 1.0}, {5, 5, 1.5}));
  moves.push_back(line(1, {50, 0, 0.4}, {60, 0, 0.4}));
  moves.push_back(line(2, {4.99, 5.01, 1.501}, {5.02, 4.98, 1.502}));
  const Measured m = measure(moves);
  EXPECT_EQ(m.crossings, 0u);
}

TEST(LayerGaps, ALayerKilometresWideIsMeasuredOnASmallGrid) {
  // A broken file's lines 1.8 km long and a curved one across them: a grid of 1 mm cells would
  // be 3 × 10^12 of them; at most 512 along a side, the crossing is still exact.
  std::vector<PrintMove> moves;
  moves.push_back(line(0, {-9e5, 0, 0.2}, {9e5, 0, 0.2}));
  moves.push_back(line(0, {-9e5, 1e5, 0.2}, {9e5, 1e5, 0.2}));
  moves.push_back(line(1, {3, -1, 0.4}, {3, 1, 0.42}));
  moves.push_back(line(1, {0, 2e6, 0.4}, {1, 2e6, 0.4}));  // past 1 km: left out
  const Measured m = measure(moves);
  ASSERT_EQ(m.crossings, 1u);
  EXPECT_NEAR(m.min, 0.21, 1e-9);
}

}  // namespace
}  // namespace nonplanar
