// Stage toolpaths: perimeters, skins, infill and skirt for every layer, ordered, each path
// carrying its own height per point so non-planar paths can use the same types.
#pragma once

#include <string_view>
#include <vector>

#include "nonplanar/slice.hpp"

namespace nonplanar {

enum class ExtrusionRole {
  external_perimeter,
  perimeter,
  internal_infill,
  solid_infill,
  top_solid_infill,
  skirt,
  support,  ///< another slicer's supports (the built-in engine prints none)
};
/// PrusaSlicer's ;TYPE: names ("External perimeter", "Internal infill", "Skirt/Brim", ...).
const char* role_name(ExtrusionRole r);
/// The role of a ;TYPE: name, PrusaSlicer's and OrcaSlicer's ("Overhang perimeter" is an
/// external one, "Ironing" a top skin's, "Brim" a skirt's, "Support material interface" and
/// OrcaSlicer's "Support transition" supports); anything else is solid infill.
ExtrusionRole role_from_name(std::string_view type);

/// One extrusion: a polyline (closed loops repeat their first point at the end). points[i]
/// carries its z; height[i] is the layer thickness under point i (mm); width in mm.
struct ExtrusionPath {
  ExtrusionRole role = ExtrusionRole::perimeter;
  double width = 0.45;
  double speed = 40;  ///< mm/s
  std::vector<Vec3> points;
  std::vector<double> height;
  /// The plate object it prints (PlateObjects' index; 0 for one object). In another slicer's
  /// file mapped back: 0 the planned part's, 1 another object's, kept as written.
  int object = 0;
};

struct LayerToolpaths {
  double z = 0, height = 0.2;        ///< nominal top of the layer and its thickness
  std::vector<ExtrusionPath> paths;  ///< in print order
  bool nonplanar = false;            ///< some point leaves the plane z (travels must lift)
  double max_z = 0;                  ///< highest point of the layer (travel clearance)
  double max_slope = 0;              ///< steepest |dz| / dxy of its paths (short-hop clearance)
};

/// Builds the paths of every layer from its islands. Errors: invalid_argument, cancelled.
Expected<std::vector<LayerToolpaths>> make_toolpaths(const std::vector<SlicedLayer>& layers,
                                                     const ToolpathParams& params,
                                                     const Context& ctx);

/// Centre-line spacing of adjacent beads of width w and height h (Slic3r's bead: a
/// rectangle with semicircular ends): w − h·(1 − π/4). A bead's cross-section is h·spacing.
double bead_spacing(double width, double height);

/// Filament length (mm) per mm of path for a bead of width w, height h (Slic3r's model: the
/// bead's cross-section over the filament's, times the extrusion multiplier).
double filament_per_mm(double width, double height, const GcodeParams& g);

}  // namespace nonplanar
