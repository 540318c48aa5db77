// Stage deform ("plane normalisation", DESIGN.md §2 step 5): map the mesh so the curved
// layers become planar, (x, y, z) ↦ (x, y, ζ(T(x, y, z))), subdividing where the map bends.
#pragma once

#include "nonplanar/context.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar {

struct NormalizeParams {
  double tolerance = 0.005;  ///< max distance between the mapped mesh and the exact map, mm
  int max_rounds = 12;       ///< edge-splitting rounds at most
};

struct NormalizedMesh {
  TriangleMesh mesh;
  std::size_t edges_split = 0;
  int rounds = 0;
};

/// Splits every edge whose mapped midpoint is farther than the tolerance from the mapped
/// chord (conforming: both faces of an edge split it), then maps every vertex. A closed,
/// consistently oriented input stays so. Errors: invalid_argument, cancelled.
Expected<NormalizedMesh> normalize_mesh(const TriangleMesh& mesh, const LayerField& field,
                                        const NormalizeParams& params, const Context& ctx);

}  // namespace nonplanar
