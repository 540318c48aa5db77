// One patch's stack: choose the plane c and the count N, optimise the intermediate layers,
// measure the figures and decide whether it is printable.
#pragma once

#include "nonplanar/context.hpp"

#include <memory>
#include <string>

#include "core/column_caster.hpp"
#include "layers/banded_field.hpp"
#include "layers/faceted_top.hpp"
#include "layers/patch_raster.hpp"
#include "layers/printability_cost.hpp"

namespace nonplanar::layers {

struct StackResult {
  LayerStack stack;
  Band band;            ///< valid when failure is empty
  std::string failure;  ///< why the patch falls back to planar, or empty
  /// With an unfitted top: the facets did not decide (every check they answer passed, or a
  /// sample of the patch lies off them); build it again with the fitted surface.
  bool needs_fit = false;
};

/// What build_stack decides before its optimiser: the checks (slope, relief, the plane c and
/// count N, material under and above the patch), and what they leave for finish_stack. With
/// LayerParams::faceted_top these read the facets only, so they run on the patch's rectangle
/// unfitted (fit_rectangle) and the rest resumes once the fit is there (fit_for_plan: the
/// checks were done twice and the blend's rasters waited on, a fifth of the sine roof's slice).
struct StackStart {
  StackResult result;   ///< refused (failure), or needs_fit as build_stack says
  bool passed = false;  ///< every check passed: finish_stack may go on from here
  // What finish_stack goes on from.
  bool fitted = false;              ///< the checks read a fitted top (the grid has its basis)
  Vec2 origin{0, 0}, extent{0, 0};  ///< of the top the checks read (the grid's rectangle)
  double step = 0;                  ///< the fine grid's spacing, mm
  PatchRaster raster;               ///< the patch's own, for the grids' masks
  StackGrid grid;                   ///< the fine grid (its basis only when fitted)
  std::vector<double> H;            ///< the faceted top at the grid's samples (faceted_top)
  std::vector<Vec2> dH;             ///< and its gradient
  std::vector<int> off_facets;      ///< samples off the facets, read from the fit when there
  double zmin = 0, zmax = 0;        ///< the top's range over the patch, mm
  double fade = 0, blend = 0;       ///< the band's fade and blend widths, mm
  // The blend's raster and the band's faceted top (prepare_blend), built once.
  bool blend_ready = false;
  PatchRaster wide;
  FacetedTop band_facets;
  /// The optimiser's grid of about 40 × 40 samples, built on `on` (stays_even's; finish_stack
  /// takes it when its top is that one, else builds its own).
  struct Coarse {
    HeightField on;
    StackGrid grid;
  };
  std::shared_ptr<const Coarse> coarse;
};

/// build_stack's checks (see there); `top` fitted or the rectangle unfitted.
StackStart start_stack(const TriangleMesh& mesh, const Patch& patch, int patch_id,
                       const HeightField& top, const ColumnCaster& columns,
                       const LayerParams& params, const PlanarLayers& planar);
/// The blend's raster and the band's faceted top for a start that passed: they depend only
/// on the facets and the start's figures, so they can be built while the top is fitted.
void prepare_blend(StackStart& start, const TriangleMesh& mesh, const Patch& patch,
                   const LayerParams& params);
/// Whether the optimiser would leave the even stack over `top` (fitted, the start's rectangle)
/// as it is: its cost's gradient there is under the solver's tolerance, as it is unless a limit
/// is active (the even interpolation makes every t_ik and every gradient difference equal). Then
/// with LayerParams::faceted_top the layers are c + (1 − i/N)(H − c), whatever the fit: a
/// refinement of the fit would change nothing but rounding. Keeps the optimiser's grid in the
/// start for finish_stack.
bool stays_even(StackStart& start, const HeightField& top, const LayerParams& params);
/// The rest of build_stack from a start that passed, with the patch's fitted `top` (whose
/// rectangle is the start's): the optimiser, the figures, the band.
StackResult finish_stack(StackStart start, const TriangleMesh& mesh, const Patch& patch,
                         const HeightField& top, const LayerParams& params, double initial_power,
                         const Context& ctx);

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
