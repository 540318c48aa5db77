// Where a shell prints when the part stands above its top somewhere (a curved hood beside a
// taller cabin, a curved ring round a raised lip): the region R of the shell's raster where
// nothing of the part is above H, and when in the core's order the shell is printed.
//
// Notation as in shell_plan.hpp: H the shell's top on its raster; t, N its layers; z_k the
// core's boundaries. R = {nodes with nothing of the part more than 0.02 mm above H}, grown
// outward by nothing and shrunk by one node at its edge; outside R the core prints every layer
// whole. a(d) the head's allowance (toolhead.hpp) at a distance d from the nozzle, h the layer
// height. z_ins: the shell is printed after the core's layers up to z_ins and before the part
// of every later layer that lies outside R.
//
// Why one z_ins works: material outside R printed before the shell stands at most z_ins, and
// the nozzle on the shell at p is at U_0(p) = H(p) − (N − 1)·t at its lowest (the shell's
// lowest layer); material outside R printed after it starts above z_ins, and the shell under p
// reaches H(p). So within a(d) of the material outside R,
//   H(p) − a(d) − h/4 ≤ z_ins ≤ U_0(p) + a(d) + h/4
// (the check's collision is a rise of more than h/2 over a(d)). Both hold only where
// 2·a(d) + h/2 ≥ (N − 1)·t: nothing may stand above the shell within about a millimetre of it
// (0.6 mm with a 45° cone and 0.2 mm layers, from the beads' centres), and beyond that the
// foot of what stands above must be about level. When no z_ins fits every p, the shell is
// refused and the gate never sees it. (Letting R give up the nodes that break this does not
// work: a node left out is printed planar to the top's own height beside the shell, which is
// again material standing above the shell's lower layers within a millimetre, and so on.)
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "layers/faceted_top.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar::layers {

struct ShellRegion {
  /// +1 at the nodes of R, −1 elsewhere, on H's raster (its marching-squares contour at 0 is
  /// R's outline); empty when R is the whole raster (nothing of the part stands above H).
  FacetedTop mask;
  /// The interval z_ins must lie in, mm (−inf … +inf when nothing outside R is within the
  /// head's reach of the patch).
  double z_lo = -std::numeric_limits<double>::infinity();
  double z_hi = std::numeric_limits<double>::infinity();
  /// Why no shell can print here (empty: it can): the patch lies mostly under other material,
  /// or no z_ins fits; names a place.
  std::string refused;
};

/// Inputs: the placed mesh, whether each face is one of the shell's patches (size = faces),
/// H, how far the shell's lowest layer's top lies under H ((N − 1)·t, mm), and the printer's
/// layer height and head. Output: R and z_ins's interval, or `refused`.
ShellRegion shell_region(const TriangleMesh& mesh, const std::vector<char>& in_patch,
                         const FacetedTop& top, double lowest, const LayerParams& p);

}  // namespace nonplanar::layers
