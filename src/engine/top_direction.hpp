// The direction of a shell's top-skin lines: up and down its top's slopes.
//
// Notation: n a facet's unit normal, g = (n_x, n_y)/|(n_x, n_y)| the direction its slope
// rises or falls along, A its area; J = Σ A·g·gᵀ over the top's sloped facets (the structure
// tensor); e₁ ≥ e₂ J's eigenvalues, v₁ e₁'s eigenvector.
//
// Why: beads laid along a slope's contours sit side by side 0.45 mm apart at heights
// 0.45·tan θ apart (0.16 mm on a 20° slope), each one a ridge above the next; beads laid up and
// down the slope lie beside beads at their own heights, so the top between them is level
// across the lines. `check` on the shell's top at 0°, 45° and 90°: the car 78.9/85.5/87.0 %
// within 0.03 mm, the ankle base 68.7/71.7/72.0 % (both slope along y), Benchy 82.0/81.6/77.1 %
// (along x). A top whose slopes face every way (a dome) has no such direction.
#pragma once

#include <optional>

#include "layers/shell_plan.hpp"
#include "nonplanar/mesh.hpp"

namespace nonplanar {

/// Inputs: the placed mesh and a shell's plan over it (its top H and region R); slopes
/// counted from min_deg to max_deg (degrees from horizontal).
/// Output: v₁'s angle from +x, degrees in [0, 180), over the up-facing facets within those
/// slopes whose centroids lie on H (within 0.3 mm) and inside R; none when they have no area
/// or their directions spread too evenly ((e₁ − e₂)/(e₁ + e₂) < 0.25, a dome's top).
std::optional<double> top_slope_direction(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                          double min_deg, double max_deg);

}  // namespace nonplanar
