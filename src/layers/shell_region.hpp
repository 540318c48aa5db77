// Where a shell prints when the part stands above its top somewhere (a curved hood beside a
// taller cabin, a curved floor inside a raised rim), and when each piece of it is printed.
//
// Notation as in shell_plan.hpp: H the shell's top on its raster; U_j its layer j's top; z_k the
// core's boundaries. R = {nodes with nothing of the part more than 0.02 mm above H, where H is
// no steeper than max_angle}, shrunk by one node at its edge; outside R the core prints every layer
// whole. d(p) the distance from p to the nodes outside R; a(d) the head's allowance
// (toolhead.hpp) at distance d from the nozzle; m = h/4; s(p) = L(d(p)) + m the slack, L the
// largest k-Lipschitz function under a, k = 0.12.
//
// The order: a point p of shell layer j is given a time τ = clamp(g(U_j(p)), U_j(p) − s⁻(p),
// U_j(p) + s(p)), s⁻ = min(s, t − a − 0.01, h/2 − 0.01) (so the core under p, up to
// U_0 − (t − a), comes first, and p rises less than h/2 over the core printed after it), and
// printed right after core layer k, the last with z_k <= τ (after the whole core when none is
// above it; a path whose τ passes several z_k at once is cut at each). g is a non-decreasing step
// function of a few heights (shell_levels.hpp) that the most of the patch can take, so most of the
// shell goes at a few times, as a few pieces per layer; next to what stands above, the shell
// follows the wall up in bands of the core's layer height, with a seam between bands (a shell
// banded over more than half its patch is refused: each band is printed apart). Where faces given
// as `kept_out` (an overhang under the shell) come within kept_depth under H, the nodes are left
// out of R like what stands above. Why it is safe:
// material of the core printed before p stands at most τ <= U + s, and after p starts above
// τ >= U − s, with s <= a(d) + m (the check's collision is a rise of more than h/2 over a(d));
// and of two shell points, the one printed first is never higher than the other by more than
// k·|p − q| (about; see kSlope), under the nozzle's cone: if it is higher, g(U(p)) >= g(U(q)),
// so one of them is clamped, and each case of τ(p) < τ(q) bounds U(p) − U(q) by a difference
// of k-Lipschitz slacks (s or s⁻).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "layers/faceted_top.hpp"
#include "layers/shell_levels.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar::layers {

/// "WHAT at (x, y, z)", the place a shell notice names (mm, two decimals).
std::string notice_at(const char* what, const Vec3& p);

/// Why a shell banded over `banded` (a share) of its patches is refused at shell_max_banded
/// `limit`, naming `near` (where the part first stands above H, mm).
std::string banded_refusal(double banded, const Vec2& near, double limit);

struct ShellRegion {
  /// +1 at the nodes of R, −1 elsewhere, on H's raster (its marching-squares contour at 0 is
  /// R's outline); empty when R is the whole raster (nothing of the part stands above H).
  NodeMask mask;
  /// s(p) on H's raster, mm; empty with an empty mask.
  FacetedTop slack;
  /// g: the heights most of the patch can be printed at (shell_levels.hpp); empty with an
  /// empty mask.
  ShellLevels levels;
  /// The share of the patch's nodes that can take no height of g, printed in bands beside what
  /// stands above (more than half: refused).
  double banded = 0;
  /// Where the part first stands above H (x, y, mm): the place a banded shell's refusal names.
  Vec2 stands_at{0, 0};
  /// The patches' area outside R, mm² (printed planar by the core).
  double left_out = 0;
  /// Why the core prints some of the patches (left_out > 0), each naming a place: the part
  /// stands above it, or H is steeper there than max_angle.
  std::vector<std::string> why_out;
  /// Why no shell can print here (empty: it can): the patch lies mostly under other material,
  /// or would be banded over more than half; names a place.
  std::string refused;
};

/// Inputs: the placed mesh, whether each face is one of the shell's patches (size = faces),
/// faces to be left out of R where they reach higher than H − kept_depth (mm: an overhang too
/// close under the shell's bottom; empty or size = faces), H, how far a point may be printed before
/// its height (`below`, mm: the shell's lowest layer must come after the core under it) and the
/// printer's layer height and head; `framed`: H covers only the patches' surroundings, and R
/// stops short of its edge (the core prints everything past it). Output: R, the slack and g, or
/// `refused`.
ShellRegion shell_region(const TriangleMesh& mesh, const std::vector<char>& in_patch,
                         const std::vector<char>& kept_out, double kept_depth,
                         const FacetedTop& top, double below, const LayerParams& p,
                         bool framed = false);

}  // namespace nonplanar::layers
