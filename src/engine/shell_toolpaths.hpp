// Toolpaths of a shell plan (layers/shell_plan.hpp): the planar core, each layer cut back to
// where it lies under the shell's reach, then the shell's curved layers on top of it (where the
// part stands above the shell's top, the shell's pieces go between the core's layers).
#pragma once

#include <vector>

#include "layers/shell_plan.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// Inputs: the placed mesh, accepted plans (refused empty; layers::choose_shells: one core,
/// several only where the part stands above each; nothing orders the points of two shells
/// beside each other, so the gate must check the result) and the print settings.
/// Output: the core's layers bottom to top, then the shells' lowest to highest, in print order;
/// with regions (plan.region), each shell point is printed right after the core's last layer
/// whose top is at most its plan's slot_level there, so the shells' layers come in pieces
/// between the core's. Every point's height is the thickness under it (a shell's lowest layer
/// fills the core's stairs). Errors: those of slicing, normalisation and mapping; cancelled.
///
/// With `stacks` (a field of curved stacks whose planar layers are the core's boundaries:
/// plan_shell's even_core), the core is sliced on the mesh normalised by it and mapped back
/// through it, so it holds the stacks' curved layers too. Their bands must lie clear of where
/// the shells cut the core (the cut is made at the core's planar heights).
struct CoreStacks {
  const LayerField* field = nullptr;
  MapBackParams map_back;
};
Expected<std::vector<LayerToolpaths>> shell_toolpaths(const TriangleMesh& mesh,
                                                      const std::vector<layers::ShellPlan>& plans,
                                                      const PrintConfig& print, const Context& ctx,
                                                      const CoreStacks& stacks = {});

}  // namespace nonplanar
