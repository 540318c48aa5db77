// Patches: connected components of painted faces, cut at discontinuities and creases.
#pragma once

#include <vector>

#include "analysis/facet_selection.hpp"
#include "nonplanar/analysis.hpp"

namespace nonplanar::analysis {

/// Faces join a patch when they are painted, not discontinuous, and share a manifold edge
/// that is not a crease. Each patch gets its statistics and verdict from params
/// (min_patch_area, min_layer_height). Sorted by decreasing area; *face_patch gets F entries.
std::vector<Patch> extract_patches(const TriangleMesh& mesh, const MeshTopology& topo,
                                   const FaceGeometry& geom, const std::vector<char>& painted,
                                   const std::vector<char>& discontinuous,
                                   const std::vector<char>& crease, const AnalysisParams& params,
                                   std::vector<int>* face_patch);

}  // namespace nonplanar::analysis
