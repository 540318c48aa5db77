// Top skins of make_toolpaths (src/toolpaths/make_toolpaths.cpp) where the layers above are cut
// back: without `covers` the cut exposes a top and the layers under it turn solid; with
// `covers` (a shell prints over the cut) they stay sparse.
#include <gtest/gtest.h>

#include "nonplanar/toolpaths.hpp"

namespace nonplanar {
namespace {

ExPolygon square(double x0, double x1) {
  return {{{x0, 0}, {x1, 0}, {x1, 20}, {x0, 20}}, {}};
}

// Solid infill length of layer k in the right half (both ends past x = 10.3), mm.
double solid_right(const std::vector<LayerToolpaths>& t, std::size_t k) {
  double len = 0;
  for (const ExtrusionPath& p : t[k].paths) {
    if (p.role != ExtrusionRole::solid_infill && p.role != ExtrusionRole::top_solid_infill)
      continue;
    for (std::size_t i = 1; i < p.points.size(); ++i)
      if (p.points[i].x() > 10.3 && p.points[i - 1].x() > 10.3)
        len += (p.points[i] - p.points[i - 1]).norm();
  }
  return len;
}

TEST(Skins, CoversKeepTheLayersUnderACutSparse) {
  // 14 layers of a 20 × 20 mm square; from layer 8 up only its left half is printed.
  std::vector<SlicedLayer> layers(14);
  for (std::size_t k = 0; k < layers.size(); ++k) {
    layers[k].z_bottom = 0.2 * static_cast<double>(k), layers[k].z_top = layers[k].z_bottom + 0.2;
    layers[k].islands = {k >= 8 ? square(0, 10) : square(0, 20)};
  }
  ToolpathParams p;  // 5 top solid layers, 4 bottom
  auto cut = make_toolpaths(layers, p, {});
  ASSERT_TRUE(cut);
  for (std::size_t k = 3; k <= 7; ++k) EXPECT_GT(solid_right(*cut, k), 50.0) << k;
  // The same with the right half covered by something printed later.
  for (std::size_t k = 8; k < layers.size(); ++k) layers[k].covers = {square(0, 20)};
  auto covered = make_toolpaths(layers, p, {});
  ASSERT_TRUE(covered);
  for (std::size_t k = 4; k <= 7; ++k) EXPECT_EQ(solid_right(*covered, k), 0.0) << k;
  // The covered layers' own paths are unchanged (covers only affect the skins below).
  EXPECT_EQ((*covered)[10].paths.size(), (*cut)[10].paths.size());
}

}  // namespace
}  // namespace nonplanar
