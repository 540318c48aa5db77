// The print head as the collision model sees it (DESIGN.md §3): a nozzle cone under a heater
// block, and optionally the rest of the head (block offset from the nozzle, fan duct, probe)
// as a stack of convex polygons by height above the nozzle tip. One description, read from the
// profile, used alike by layer planning, the slicer's safety gate, `check` and the writers.
//
// Notation: d is an XY offset from the nozzle axis (mm); a(d) is the allowance at d, how far
// material there may stand above the nozzle tip before it touches the head (mm).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// The head from `height` mm above the nozzle tip upward covers `polygons` (convex, XY in mm
/// relative to the nozzle axis, either winding).
struct ToolheadSlice {
  double height = 0;
  std::vector<std::vector<Vec2>> polygons;
};

/// Profile keys: nozzle_tip_radius, nozzle_cone_angle, heater_block_radius,
/// heater_block_clearance, toolhead_shape (a JSON file, docs/toolhead.md).
struct Toolhead {
  double tip_radius = 0.4;       ///< flat of the nozzle tip, mm
  double cone_angle_deg = 45.0;  ///< the nozzle's outer wall above horizontal
  /// The round default: a heater block covering |d| <= block_radius from block_clearance up.
  /// Used when `shape` is empty.
  double block_radius = 8.0, block_clearance = 4.0;
  /// The rest of the head, replacing the round block when not empty.
  std::vector<ToolheadSlice> shape;
  std::string shape_name;  ///< where `shape` came from (for headers and messages)

  /// Farthest XY distance from the nozzle axis that any part of the head covers (mm).
  double reach() const;
  /// The same for the parts of the head lower than `height` mm above the tip (the cone up to
  /// there, the slices or block under it): material standing at most `height` over the tip
  /// farther off than this touches nothing.
  double reach_under(double height) const;
  /// Lowest height above the tip of anything but the nozzle cone (mm).
  double clearance() const;
  /// Where the nozzle cone meets the head above it (mm above the tip): the block_clearance of
  /// the round head, else the lowest slice over the nozzle axis.
  double cone_top() const;
  /// One line for G-code headers and reports: "round (tip 0.40 mm, cone 45.0 deg, block r
  /// 8.0 mm from 4.0 mm)" or "prusa-mk3s (tip 0.40 mm, cone 45.0 deg, 4 slices, reach 78 mm)".
  std::string describe() const;
};

/// The allowance a(d) of one head, with what every query needs worked out once (collision
/// searches ask millions of times).
class HeadClearance {
 public:
  /// `tallest`: how far material can stand above the nozzle tip at most (mm), e.g. the print's
  /// height. Slices from that height up can touch nothing, so they are dropped and reach()
  /// shrinks: a head whose gantry spans the bed need not make every search that wide.
  explicit HeadClearance(const Toolhead& head,
                         double tallest = std::numeric_limits<double>::infinity());
  /// a(d): +inf where nothing of the head is above d.
  double allowance(const Vec2& d) const;
  /// a(d) of everything but the nozzle cone (the heater block, the shape's slices).
  double block_allowance(const Vec2& d) const;
  /// A lower bound of a(d) over the offsets in the box [lo, hi] (mm).
  double allowance_lower_bound(const Vec2& lo, const Vec2& hi) const;
  double reach() const { return reach_; }

 private:
  double at(const Vec2& nearest, bool in_box, const Vec2& lo, const Vec2& hi, bool cone_too) const;
  Toolhead head_;  // a copy (trimmed to `tallest`): the caller's may not outlive this
  bool shaped_;    // head_.shape was not empty before trimming (else the round block)
  double tan_cone_, cone_top_, reach_;
};

/// How a travel over a curved layer clears what is printed (DESIGN.md §3), the one rule every
/// writer follows. Material printed so far lies below the layer's highest point `layer_top`,
/// so a long travel (over 0.6 mm, or changing height by over 0.1 mm) rises `lift` above the
/// highest of it and both ends. A short hop (between neighbouring infill lines) only rises
/// 0.05 mm above what the layer can hold within reach of it: no steeper than `slope` (a
/// tangent), nothing of it within the tip's radius of the hop stands higher than its ends by
/// more than slope · (d / 2 + tip_radius). Returns the height to travel at, or NaN where the
/// straight move is safe (a hop whose rise is under 0.05 mm).
double travel_height(const Vec3& from, const Vec3& to, double layer_top, double slope,
                     double tip_radius, double lift);

/// The `lift` of a long travel over a curved layer for a printer whose z-hop is
/// `retract_lift` (mm): that, but at least 0.3 mm.
double travel_lift(double retract_lift);

}  // namespace nonplanar
