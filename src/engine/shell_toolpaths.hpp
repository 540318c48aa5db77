// Toolpaths of a shell plan (layers/shell_plan.hpp): the planar core, each layer cut back to
// where it lies under the shell's reach, then the shell's curved layers on top of it, then
// (where the part stands above the shell's top) the rest of the core.
#pragma once

#include <vector>

#include "layers/shell_plan.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// Inputs: the placed mesh, an accepted plan (plan.refused empty) and the print settings.
/// Output: the core's layers bottom to top (above plan.insert_z only their part in R), then the
/// shell's lowest to highest, then the core's layers above insert_z outside R, in print order; every point's height is the thickness under it (the shell's lowest layer fills the
/// core's stairs). Errors: those of slicing, normalisation and mapping; cancelled.
Expected<std::vector<LayerToolpaths>> shell_toolpaths(const TriangleMesh& mesh,
                                                      const layers::ShellPlan& plan,
                                                      const PrintConfig& print, const Context& ctx);

}  // namespace nonplanar
