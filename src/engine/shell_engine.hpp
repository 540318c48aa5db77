// A shell over a planar core (layers/shell_plan.hpp) printed by an external engine
// (PrusaSlicer): over the whole top, one run of the part with the shell's slab above it, split
// and stitched into one program; where the part stands above the shells, one run of the part
// alone, the shells' pieces written between its layers.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "engine/engine_route.hpp"
#include "layers/shell_plan.hpp"

namespace nonplanar {

/// Why a shell the part stands above is not printed by one slicer run (it cannot stop its core
/// part-way for the shell's pieces): for prepare (`slice --engine` prints its pieces between
/// the engine's core layers, shell_pieces_with_engine).
inline constexpr std::string_view kOneRunShellWhole =
    "in one slicer run a shell prints only where the part stands nowhere above its top "
    "('nonplanar slice' prints this one)";

struct EngineShell {
  std::string gcode;                   ///< the whole program, without our header
  std::vector<LayerToolpaths> layers;  ///< core bottom to top, then the shell, for the gate
};

/// The part above z0 of a closed mesh, open along the cut (nothing is sliced there: an engine
/// slicing it from z0 up sees closed sections). Triangles crossing z0 are clipped; the cut
/// points of an edge are computed from its ends in one order, so neighbours agree.
TriangleMesh cut_below(const TriangleMesh& mesh, double z0);

/// What one slicer run of a shell is given (prepare's 3MF, the engine route's run): the placed
/// part, sliced on the core's boundaries z_0 … z_s, and above z_s the shell's slab (the part
/// normalised by ShellField(plan, base), base = z_s + t, cut below z_s: its layers are the
/// shell's, ζ = base + j·t). The layer z_s … z_s + t under the slab (the normalised part just
/// under the shell's bottom) holds it up, so the slicer prints the slab's first layer as on a
/// part, not as a bridge; the split drops it. The part's own top above z_s joins the slab's
/// layers, which cover it (the core's layers above z_s are all cut away under the shell).
/// Why not two objects: a slicer drops every object onto the bed and prints its first layer
/// with first-layer settings.
struct ShellStack {
  TriangleMesh mesh;               ///< the part's faces, then the slab's (open along its cut)
  std::vector<double> layer_tops;  ///< mm: z_1 … z_s, then z_s + t … z_s + (N + 1)·t
  double base = 0;                 ///< mm: z_s + t, the ζ of the shell's lowest layer's bottom
  /// A box from just above z_s over the top, 1 mm wider than the part all round: the slab's
  /// underside floats over the part's top, and a slicer with supports on would support it
  /// (on the rib: 53 min of columns against 35 without); it supports the part's own only.
  TriangleMesh support_blocker;
};

/// Inputs: the placed mesh, an accepted plan with no region (the whole top). Output: the
/// stack above. Errors: the normalisation's (a map that would fold); cancelled.
Expected<ShellStack> shell_stack(const TriangleMesh& placed, const layers::ShellPlan& plan,
                                 const Context& ctx);

/// Inputs: the placed mesh, an accepted plan (plan.refused empty), the route (its engine is
/// PrusaSlicer). Output: one program: the run's start G-code and core layers, each cut back to
/// where z_k <= B + a (as shell_toolpaths), then the layers above the core mapped onto the
/// shell (entered from where the core ended, its retraction given back), then the run's end
/// G-code. The run slices shell_stack's mesh on its layer tops (a layer-height profile), and
/// its file is split as post-process splits a prepared shell's (shell_split.hpp). Errors:
/// those of the engine, the split and the mapping; cancelled.
Expected<EngineShell> shell_with_engine(const TriangleMesh& mesh, const layers::ShellPlan& plan,
                                        const EngineRoute& job, const Context& ctx);

/// Inputs: the placed mesh, accepted plans of shells the part stands above (each plan.region
/// set; layers::choose_shells: one core), the route (its engine is PrusaSlicer). Output: one
/// program: the engine's run of the part alone on the core's boundaries, mapped, each layer cut
/// back inside each shell's R where z_k > B + a (as the built-in core), and between its layers
/// the shells' pieces (shell_slots: the built-in engine's curved layers, each point after the
/// core's layers up to its slot level; an engine run cannot stop its core part-way to print
/// them), written into the program where they go (ForeignMapOptions::before_layer). The
/// shells are sliced beside the engine's run. Errors: those of the engine and the mapping, and
/// unsupported for a core off the planned boundaries; cancelled. Each plan's `slack` is spent
/// (freed) once the pieces are cut: the bunny's four were 37 MB while its core was mapped.
Expected<EngineShell> shell_pieces_with_engine(const TriangleMesh& mesh,
                                               std::vector<layers::ShellPlan>& plans,
                                               const EngineRoute& job, const Context& ctx);

/// The core's G-code (a planar program sliced on plan.core's boundaries) mapped and cut back
/// under the shell, as shell_with_engine maps its first run; the moves of `others` (0-based
/// lines of core_text; empty: none) are other objects', left as written and neither cut nor
/// held to the boundaries. Errors: those of the mapping, and unsupported for a layer of the
/// part off the planned boundaries (the profile was not followed). The text is consumed as it
/// is mapped (map_foreign_gcode's consuming form).
Expected<ForeignGcode> map_shell_core(std::string core_text, const layers::ShellPlan& plan,
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
