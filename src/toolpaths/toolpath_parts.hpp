// Building blocks of make_toolpaths, one concept per file: perimeter loops, infill lines,
// skin classification and path ordering.
//
// Notation: w bead width, h layer height, s = w − h(1 − π/4) the spacing of adjacent beads
// (their cross-section is h·s, so beads s apart fill an area exactly).
#pragma once

#include <vector>

#include "core/polygon_ops.hpp"
#include "nonplanar/slice.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar::paths {

using clip::ExPolygons;
using clip::Polyline;

/// Perimeter centre lines of one island, outermost first: loops[0] are the external
/// perimeter (the island shrunk by w_ext / 2), each next set s further in. *inner gets the
/// area left for infill (the last loops shrunk by s / 2), or the island if count is 0.
std::vector<std::vector<Polygon>> perimeter_loops(const ExPolygons& island, int count, double w_ext,
                                                  double s, ExPolygons* inner);

/// Parallel lines at `angle_deg` spaced `spacing` (aligned to a global grid so layers match),
/// clipped to `region` shrunk by s / 2 so the beads stay inside it. With `fit` (solid fill),
/// each island's lines instead run evenly from its one extreme across the lines to the other,
/// the first and last s / 2 inside them, at the spacing nearest `spacing` within ±20 %: a
/// side along the lines gets a line beside it, not a gap of up to a spacing (PrusaSlicer's
/// full infill adjusts its spacing the same way). Each line comes with its spacing, mm.
struct InfillLine {
  Polyline line;
  double spacing = 0;
};
std::vector<InfillLine> infill_lines(const ExPolygons& region, double angle_deg, double spacing,
                                     double s, bool fit = false);

/// The nearest-neighbour order of paths from `from`, reversing open paths and rotating
/// closed loops (front == back) so each starts nearest to the nozzle.
void order_paths(std::vector<ExtrusionPath>& paths, Vec2 from);

}  // namespace nonplanar::paths
