// A patch rasterised in XY: which cells it covers and each cell's distance to it.
#pragma once

#include <vector>

#include "nonplanar/analysis.hpp"

namespace nonplanar::layers {

struct PatchRaster {
  Vec2 origin{0, 0};  ///< centre of cell (0, 0)
  double cell = 0.25;
  int nx = 0, ny = 0;
  std::vector<char> mask;    ///< nx·ny, cell centre inside a patch triangle (XY)
  std::vector<double> dist;  ///< nx·ny, distance (mm) from the cell centre to the patch
  std::size_t at(int i, int j) const { return static_cast<std::size_t>(i) * ny + j; }
  double distance(double x, double y) const;  ///< nearest cell's distance (large outside)
};

/// Rasterise the patch's triangles over its XY box grown by `pad` mm, then an exact
/// Euclidean distance transform (Felzenszwalb–Huttenlocher, two 1D passes).
PatchRaster rasterize_patch(const TriangleMesh& mesh, const Patch& patch, double cell, double pad);

}  // namespace nonplanar::layers
