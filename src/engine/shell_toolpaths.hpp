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

/// One shell's curved layers, bottom to top, mapped back; each point's height the thickness
/// under it (the lowest layer's down to the core's top, filling its stairs). Inputs: the placed
/// mesh, an accepted plan, R: where it prints (layers::region_at_least of plan.region; empty:
/// everywhere), the print settings. Errors: those of normalisation, slicing and mapping.
Expected<std::vector<LayerToolpaths>> shell_curved_layers(const TriangleMesh& mesh,
                                                          const layers::ShellPlan& plan,
                                                          const std::vector<ExPolygon>& R,
                                                          const PrintConfig& print,
                                                          const Context& ctx);

/// The shells' layers (shells[i] of plans[i], as shell_curved_layers gives them) cut into the
/// pieces printed between the core's layers, whose tops are `tops` (mm, rising; K of them):
/// slot k (0 … K) holds, layer by layer, the pieces printed after the core's first k layers
/// (each point after the layers with tops up to its plan's slot_level); slot 0 is always
/// empty. Each piece's z is its highest point; its paths in the shell layer's order.
std::vector<std::vector<LayerToolpaths>> shell_slots(
    const std::vector<std::vector<LayerToolpaths>>& shells,
    const std::vector<layers::ShellPlan>& plans, const std::vector<double>& tops);

/// A slot's piece, its paths put in the order the head reaches them from `at`
/// (program::order_reach_groups: a band beside a wall is cut into pieces on all sides of it);
/// `at` becomes where the piece ends.
void order_piece(LayerToolpaths& part, const Toolhead& head, Vec2& at);

}  // namespace nonplanar
