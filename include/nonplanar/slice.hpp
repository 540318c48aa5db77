// Stage slice: planar contours of a closed mesh, as polygons with holes, per layer.
#pragma once

#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/context.hpp"
#include "nonplanar/polygon.hpp"

namespace nonplanar {

struct SlicedLayer {
  double z_bottom = 0, z_top = 0;  ///< the layer's span, mm
  double z_slice = 0;              ///< where the mesh was cut (mid-layer)
  std::vector<ExPolygon> islands;
  /// What this layer covers for the top skins of the layers below, when that is more than
  /// its islands (a core layer cut back under a shell, which covers the rest). Empty: the
  /// islands.
  std::vector<ExPolygon> covers;
};

/// Cuts the mesh at the middle of every layer (first layer first_layer_height, then
/// layer_height), chains the segments into loops through the mesh's edges, closes small
/// gaps and unions overlapping shells (non-zero rule). Parallel over layers.
Expected<std::vector<SlicedLayer>> slice_mesh(const TriangleMesh& mesh, const SliceParams& params,
                                              const Context& ctx);

/// The same cut at the given layers' z_slice (their spans are kept; islands replaced), for a
/// caller that chooses its own layer heights.
Expected<std::vector<SlicedLayer>> slice_mesh_at(const TriangleMesh& mesh,
                                                 std::vector<SlicedLayer> layers,
                                                 const Context& ctx);

}  // namespace nonplanar
