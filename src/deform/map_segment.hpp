// Mapping one planar point or segment back onto its curved layer: shared by the built-in
// engine's toolpaths (map_toolpaths.cpp) and foreign G-code (map_foreign_gcode.cpp).
//
// Notation: a planar point (x, y, ζ) lies on layer boundary t = t(ζ); its real height is
// z = z(x, y, t) and the layer under it spans t − Δt … t with Δt = t(ζ) − t(ζ − h).
#pragma once

#include "nonplanar/deform.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// A mapped point and the layer thickness under it, mm.
struct Mapped {
  Vec3 p;
  double height;
};

/// The planar point q (its layer h_planar thick) on its curved layer.
Mapped map_point(const LayerField& f, const Vec3& q, double h_planar);

/// Appends the mapped segment a → b to out (points and heights; a's image is already there),
/// cut to at most 1 mm wherever the segment meets a curved band, then split while a mapped
/// point (the midpoint, then probes params.probe_spacing apart) strays farther from its chord
/// than params.tolerance, or than half the layer's margin over params.min_layer_height.
/// depth: recursion depth (start at 0).
void map_segment(const LayerField& f, const Vec3& a, const Mapped& ma, const Vec3& b,
                 const Mapped& mb, double h, const MapBackParams& params, int depth,
                 ExtrusionPath& out);

/// Widens L's highest point (max_z) and steepest slope (max_slope, |dz| / dxy over pieces
/// longer than 1 µm in XY) by the mapped path p, which set how travels clear the layer;
/// *min_z, when given, gets its lowest point.
void add_to_reach(const ExtrusionPath& p, LayerToolpaths& L, double* min_z = nullptr);

}  // namespace nonplanar
