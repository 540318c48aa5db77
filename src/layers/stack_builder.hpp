// One patch's stack: choose the plane c and the count N, optimise the intermediate layers,
// measure the figures and decide whether it is printable.
#pragma once

#include "nonplanar/context.hpp"

#include <string>

#include "core/column_caster.hpp"
#include "layers/banded_field.hpp"

namespace nonplanar::layers {

struct StackResult {
  LayerStack stack;
  Band band;            ///< valid when failure is empty
  std::string failure;  ///< why the patch falls back to planar, or empty
  /// With an unfitted top: the facets did not decide (every check they answer passed, or a
  /// sample of the patch lies off them); build it again with the fitted surface.
  bool needs_fit = false;
};

/// top: the patch's fitted surface; or its rectangle unfitted (fit_rectangle, no control
/// points), for the checks the facets decide with LayerParams::faceted_top (slope, relief,
/// the plane and layer count, material under and above the patch): a refusal then is the one
/// the fitted surface would get, and needs_fit says the facets did not decide.
/// initial_power: the starting layers are S_i = (1 − a_i) S_f + a_i c with a_i = (i/N)^power
/// (1 is the paper's even spacing; tests start from a poor one).
StackResult build_stack(const TriangleMesh& mesh, const Patch& patch, int patch_id,
                        const HeightField& top, const ColumnCaster& columns,
                        const LayerParams& params, const PlanarLayers& planar,
                        double initial_power = 1.0, const Context& ctx = {});

}  // namespace nonplanar::layers
