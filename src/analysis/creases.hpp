// Crease detection: the angle deficit cannot see a fold between two flat faces (a roof
// ridge has K = 0), so creases are found from the dihedral angle between adjacent faces.
#pragma once

#include <vector>

#include "analysis/facet_selection.hpp"

namespace nonplanar::analysis {

/// Marks corner c = 3f + k (the edge of f starting at its k-th vertex) when both f and the
/// face across it are painted, neither is degenerate, and their normals differ by more
/// than crease_angle (radians). Returns 3F flags (each crease edge marked from both sides).
std::vector<char> find_creases(const MeshTopology& topo, const FaceGeometry& geom,
                               const std::vector<char>& painted, double crease_angle_rad);

}  // namespace nonplanar::analysis
