// The region where a rastered height field reaches a level: {(x, y) : H(x, y) >= level}, as
// polygons (marching squares on the raster's nodes, crossings interpolated along cell edges).
#pragma once

#include <vector>

#include "layers/faceted_top.hpp"
#include "nonplanar/slice.hpp"

namespace nonplanar::layers {

/// Inputs: H (node heights, mm) and a level (mm). Output: the region of the raster's box where
/// H >= level, contours counter-clockwise, holes clockwise; a saddle cell joins its two high
/// corners when the cell's mean is above the level. Past the raster's edge H counts as below
/// the level, so every contour closes; an empty vector when no node reaches the level.
std::vector<ExPolygon> region_at_least(const FacetedTop& H, double level);

}  // namespace nonplanar::layers
