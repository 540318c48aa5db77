// Where the slicer's safety gate must look for collisions (DESIGN.md §3).
//
// Notation: per band, its support is where β > 0, c its plane, S_0 its (tamed) top and L_rec
// its fade; R is the heater block's radius.
#pragma once

#include <vector>

#include "layers/banded_field.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/program.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// The layers are planar outside every band's support, and inside it below c and above
/// S_0 + L_rec (BandedField::reach). Two planar layers cannot collide (earlier material lies a
/// layer below the nozzle), so a collision needs a curved layer within R of the nozzle:
/// - `query`: per band, its support grown by R, from c up to above its top: no extrusion
///   point outside every such box can collide (find_collisions' looked_at);
/// - `material`: per band, its support grown by 2R, from c up, and no later than the last
///   layer with a point in its query box: the only material a query point can meet (it
///   must be of an earlier layer). Every box has 1 mm of slack on each side.
struct GateZones {
  std::vector<BoundingBox> query, material;
  std::vector<int> last_layer;  ///< per band: the last layer with a point in its query box
  /// Sets last_layer from the paths (layers[i] is layer i).
  void find_last_layers(const std::vector<LayerToolpaths>& layers);
  /// Can this move of layer `layer` matter to the gate (its segment's box meets a material
  /// box, no later than that box's last layer)?
  bool may_matter(const GcodeMove& m, int layer) const;
};

/// The zones of every band of `field`; R in mm.
GateZones gate_zones(const layers::BandedField& field, double R);

/// Heights where a point may meet earlier material, for a program without bands (shells over
/// a planar core): material printed before a point and no higher than it cannot reach into the
/// head, so only the points lower than the highest point printed before them count (the same
/// layer's included, which only adds points). Each span [lo, hi] holds such points' heights,
/// spans 2 mm or more apart kept apart (several shells at different heights: the bunny's tail,
/// back, head and ear); the material such a point can meet lies above its span's lo, and was
/// printed no later than the span's last_layer, the last layer with one of its points. Spans
/// in order of lo; none: nothing is out of order. In mm.
struct OutOfOrder {
  struct Span {
    double lo = 1e300, hi = -1e300;
    int last_layer = -1;
  };
  std::vector<Span> spans;
  /// Is p (printed) within a millimetre of a span?
  bool looked_at(const Vec3& p) const;
  /// May a move of `layer` reaching up to z be above a point of a span, printed before it?
  bool may_matter(double z, int layer) const;
};
OutOfOrder out_of_order(const std::vector<LayerToolpaths>& layers);

}  // namespace nonplanar
