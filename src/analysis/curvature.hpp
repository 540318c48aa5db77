// Discrete Gaussian curvature by angle deficit, and the paper's discontinuity test (§2).
//
// Notation: for a vertex v on a surface made of the faces in a mask, Θ(v) = Σ corner angles
// at v; K(v) = 2π − Θ(v) inside the surface, π − Θ(v) on its boundary; A(v) = ⅓ Σ area of
// the faces around v; K̂(v) = K(v) / A(v) (1/mm²), which approaches the Gaussian curvature
// (1/R² on a sphere of radius R) as the mesh is refined.
#pragma once

#include <vector>

#include "analysis/facet_selection.hpp"

namespace nonplanar::analysis {

/// Per-vertex curvature of the surface made of the faces with mask[f] set (all faces when
/// mask is null). deficit: V values K (radians); area: V values A (mm²); boundary: V flags
/// (on an edge with only one masked face); vertices the mask does not touch get 0.
struct VertexCurvature {
  std::vector<double> deficit;
  std::vector<double> area;
  std::vector<char> boundary;
  /// K̂ per vertex (0 where A is 0).
  std::vector<double> normalized() const;
};

VertexCurvature angle_deficit(const TriangleMesh& mesh, const MeshTopology& topo,
                              const FaceGeometry& geom, const std::vector<char>* mask);

/// The paper's test on the masked surface: v is discontinuous when K̂(v) > tau or
/// |K̂(v) − K̂(w)| > epsilon for an edge neighbour w. Only interior vertices are tested: on the
/// boundary, π − Θ measures how the outline turns, not how the surface bends.
/// Returns V flags.
std::vector<char> discontinuous_vertices(const TriangleMesh& mesh, const VertexCurvature& curv,
                                         const std::vector<char>& mask, double tau, double epsilon);

}  // namespace nonplanar::analysis
