// Which extrusions of one layer can touch: the nozzle printing one of them is clear of
// another printed before it only if the two are farther apart than the head reaches at the
// height material of the layer can stand over the nozzle. Extrusions in different groups never
// touch, so a group may be printed whole before the next without breaking an order the rules
// set inside a group (top skins low to high, DESIGN.md §3): the rule of a sloped ring's skin
// sorted by height over the whole ring sent the nozzle across its hole between two strokes.
//
// Notation: a box is [lo, hi] round an extrusion's points (mm); near = the head's reach under
// the layer's height span (Toolhead::reach_under) + the widest bead + 0.1 mm.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "nonplanar/toolhead.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar::program {

/// An extrusion's box and its bead's width (mm).
struct ReachBox {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  double width = 0.45;
  void extend(const Vec3& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
};

/// Inputs: the boxes of one layer's extrusions (or of a run of them) and the head. Output: each
/// box's group, as the index of the group's first box (boxes whose XY boxes come within near
/// of each other, directly or through others, share one).
std::vector<std::size_t> reach_groups(const std::vector<ReachBox>& boxes, const Toolhead& head);

/// Inputs: paths in print order, the head, where the nozzle is (XY, mm). Output: the order to
/// print them in (indices into `paths`): group by group, each group's paths in their own order,
/// the next group the one whose first path starts nearest to where the last one ended. Paths
/// are not reversed.
std::vector<std::size_t> order_reach_groups(const std::vector<ExtrusionPath>& paths,
                                            const Toolhead& head, Vec2 from);

}  // namespace nonplanar::program
