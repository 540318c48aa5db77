// A shell over a planar core (layers/shell_plan.hpp) printed by an external engine
// (PrusaSlicer): two runs of it, stitched into one program.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "engine/engine_route.hpp"
#include "layers/shell_plan.hpp"

namespace nonplanar {

struct EngineShell {
  std::string gcode;                   ///< the whole program, without our header
  std::vector<LayerToolpaths> layers;  ///< core bottom to top, then the shell, for the gate
};

/// The part above z0 of a closed mesh, open along the cut (nothing is sliced there: an engine
/// slicing it from z0 up sees closed sections). Triangles crossing z0 are clipped; the cut
/// points of an edge are computed from its ends in one order, so neighbours agree.
TriangleMesh cut_below(const TriangleMesh& mesh, double z0);

/// Inputs: the placed mesh, an accepted plan (plan.refused empty), the route (its engine is
/// PrusaSlicer). Output: one program: the core run's start G-code and layers, each cut back to
/// where z_k <= B + a (as shell_toolpaths), then the shell run's layers mapped onto the shell
/// (entered from where the core ended, its retraction given back), then the core run's end
/// G-code. The core run slices the mesh on the plan's layer boundaries (a 3MF layer-height
/// profile); the shell run slices the normalised mesh above ζ = 0 as a slab (no skirt,
/// first-layer settings neutral). Errors: those of the engine and the mapping; cancelled.
Expected<EngineShell> shell_with_engine(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                        const EngineRoute& job, const Context& ctx);

/// The core's G-code (a planar program sliced on plan.core's boundaries) mapped and cut back
/// under the shell, as shell_with_engine maps its first run; the moves of `others` (0-based
/// lines of core_text; empty: none) are other objects', left as written and neither cut nor
/// held to the boundaries. Errors: those of the mapping, and unsupported for a layer of the
/// part off the planned boundaries (the profile was not followed).
Expected<ForeignGcode> map_shell_core(std::string_view core_text, const layers::ShellPlan& plan,
                                      const EngineRoute& job, const Context& ctx,
                                      std::vector<char> others = {});

/// Inputs: the mapped core, the shell's G-code (its layers planes of ShellField(plan, base)),
/// the note written where the shell begins. Output: one program: the core's start and layers,
/// the shell's layers mapped onto the shell, its fan as the shell's program had it when its
/// print began, the core's end. The shell is entered from above: the nozzle rises to the
/// highest point printed + travel_lift where the core ended (on a support column beside the
/// part, or on another object of the plate taller than the shell, a layer change mapped
/// there would have gone down into it) and travels there to over the shell's first move;
/// the core's retraction is given back with the shell's first.
Expected<EngineShell> join_shell(ForeignGcode core, std::string_view shell_text,
                                 const layers::ShellPlan& plan, double base, const EngineRoute& job,
                                 const std::string& note, const Context& ctx);

}  // namespace nonplanar
