// The region where a rastered height field reaches a level: {(x, y) : H(x, y) >= level}, as
// polygons (marching squares on the raster's nodes, crossings interpolated along cell edges).
#pragma once

#include <vector>

#include "layers/faceted_top.hpp"
#include "nonplanar/polygon.hpp"

namespace nonplanar::layers {

/// region_at_least for many levels of one raster: blocks of 16 × 16 cells keep their lowest
/// and highest node, so a level only visits the cells of blocks it crosses.
class ContourIndex {
 public:
  explicit ContourIndex(const FacetedTop& H);
  std::vector<ExPolygon> region_at_least(double level) const;

 private:
  static constexpr int kBlock = 16;
  const FacetedTop& H_;
  int bx_ = 0, by_ = 0;          ///< blocks along x and y (cells −1 … n − 1)
  std::vector<double> lo_, hi_;  ///< per block; −∞ in lo_ where it touches the outer ring
};

/// Inputs: H (node heights, mm) and a level (mm). Output: the region of the raster's box where
/// H >= level, contours counter-clockwise, holes clockwise; a saddle cell joins its two high
/// corners when the cell's mean is above the level. Past the raster's edge H counts as below
/// the level, so every contour closes; an empty vector when no node reaches the level.
std::vector<ExPolygon> region_at_least(const FacetedTop& H, double level);

}  // namespace nonplanar::layers
