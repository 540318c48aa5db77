// Facet selection (paper §2): which faces a nozzle can follow.
//
// Notation: n_f = (v1 − v0) × (v2 − v0) / |…| the unit normal from the winding; θ_f the angle
// between n_f and +Z.
#pragma once

#include <vector>

#include "core/mesh_topology.hpp"
#include "nonplanar/mesh.hpp"

namespace nonplanar::analysis {

/// Per-face normals and areas. normals: F unit vectors (zero for a degenerate face);
/// areas: F values in mm²; degenerate: F flags (area below the mesh's tolerance).
struct FaceGeometry {
  std::vector<Vec3> normals;
  std::vector<double> areas;
  std::vector<char> degenerate;
};

/// Normals from the winding (stored file normals are never trusted). Faces whose area is
/// below (1e-9 · bounding-box diagonal)² are marked degenerate.
FaceGeometry face_geometry(const TriangleMesh& mesh);

/// Paint faces with θ_f < max_angle (radians). A degenerate face has no direction of its
/// own: it is painted when a non-degenerate neighbour across an edge is, so slivers do
/// not cut a patch in two. Returns F flags.
std::vector<char> select_facets(const FaceGeometry& geom, const MeshTopology& topo,
                                double max_angle_rad);

}  // namespace nonplanar::analysis
