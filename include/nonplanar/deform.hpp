// Stage deform ("plane normalisation", DESIGN.md §2 step 5): map the mesh so the curved
// layers become planar, (x, y, z) ↦ (x, y, ζ(T(x, y, z))), subdividing where the map bends.
#pragma once

#include <string>
#include <string_view>

#include "nonplanar/context.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/toolpaths.hpp"

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

struct MapBackParams {
  double tolerance = 0.01;  ///< max distance of a straight segment from its curved layer, mm
};

/// Maps toolpaths sliced from the normalised mesh back onto the curved layers:
/// (x, y, ζ) ↦ (x, y, z(x, y, t(ζ))), splitting segments until each stays within the
/// tolerance of its layer; each point's height becomes the local layer thickness there, so
/// extrusion follows it. Top skins on a slope are reordered to print from low to high.
Expected<std::vector<LayerToolpaths>> map_toolpaths_back(const std::vector<LayerToolpaths>& planar,
                                                         const LayerField& field,
                                                         const MapBackParams& params,
                                                         const Context& ctx);

/// Another slicer's G-code of the normalised mesh, mapped back, and its extrusions (as paths
/// with heights, for the same safety check as the built-in engine's).
struct ForeignGcode {
  std::string text;
  std::vector<LayerToolpaths> layers;  ///< one per ;LAYER_CHANGE of the print
};

/// Maps a planar G-code file (PrusaSlicer's or OrcaSlicer's, or ours) sliced from the
/// normalised mesh back onto the curved layers. Start and end G-code (before the first
/// ;LAYER_CHANGE; from the ;TYPE:Custom after the last extrusion type) pass untouched, as do
/// M-codes, tool changes, G4, G10/G11, G92 and the comments. Inside the print every G0/G1 is
/// mapped: extrusions resampled and their E scaled by each piece's 3D length and layer
/// thickness (as the built-in engine's paths), wipes laid on the layer, retractions kept,
/// travels over curved layers lifted above them; ;Z: and ;HEIGHT: are recomputed (the
/// layer's highest point and mean thickness); absolute or relative E as the file says.
/// Errors (parse_error, naming the line): an arc, an unknown command or word inside the
/// print, a move before the first layer, a file without ;LAYER_CHANGE.
Expected<ForeignGcode> map_foreign_gcode(std::string_view text, const LayerField& field,
                                         const MapBackParams& params, const Context& ctx);

/// Splits every edge whose mapped midpoint is farther than the tolerance from the mapped
/// chord (conforming: both faces of an edge split it), then maps every vertex. A closed,
/// consistently oriented input stays so. Errors: invalid_argument, cancelled.
Expected<NormalizedMesh> normalize_mesh(const TriangleMesh& mesh, const LayerField& field,
                                        const NormalizeParams& params, const Context& ctx);

}  // namespace nonplanar
