// The planar engines behind the pipeline: each slices a (normalised) mesh and returns its
// layers mapped back onto the curved ones, the external ones with their whole program.
#pragma once

#include <string>
#include <vector>

#include "engine/external_engine.hpp"
#include "layers/shell_plan.hpp"
#include "nonplanar/config.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/engine.hpp"
#include "nonplanar/layers.hpp"

namespace nonplanar {

/// What an engine needs of the job: which engine, the print settings (they must agree with
/// the engine's profile), the layer limits (the planar field when nothing is curved) and how
/// paths are mapped back.
struct EngineRoute {
  const EngineParams& engine;
  const PrintConfig& print;
  const LayerParams& layers;
  const MapBackParams& map_back;
  /// PrusaSlicer started before the mesh existed (start_engine_early): the first plain run of
  /// a mesh where it expects one takes it (a shell's run too). Null: each run starts its own.
  EarlyEngine* early = nullptr;
};

/// A sliced part: its layers mapped back (the gate's input) and, from an external engine,
/// the whole program (its start and end G-code and settings kept; without our header).
struct EngineOutput {
  std::vector<LayerToolpaths> layers;
  std::string gcode;  ///< empty: the built-in engine's (write `layers` with make_gcode)
};

/// Inputs: the mesh to slice (the normalised one, or the placed mesh when nothing is
/// curved), the plan's field (null: nothing is curved, the layers are kept as sliced).
/// Output: the built-in engine's layers, or the external engine's program mapped back (its
/// layers as mapped, for the gate's thickness check and zones; slopes are judged on the text).
/// Errors: those of the stages and of the engine (the message names it), cancelled.
Expected<EngineOutput> slice_with(const TriangleMesh& to_slice, const LayerField* field,
                                  const EngineRoute& route, const Context& ctx);

/// The shell plans printed by the route's engine: the built-in core and shells
/// (shell_toolpaths), or the external engine's run of the part with the shell's slab above it,
/// split and stitched into one program (shell_with_engine: one shell only). Errors: unsupported
/// (the engine's core is off the plan's boundaries), those of the stages and the engine, cancelled.
/// `stacks`: curved stacks in the core (shell_toolpaths' CoreStacks field), built-in engine only
/// (else unsupported). Through an engine, a plan's `slack` may be spent (freed) once its
/// shell's pieces are cut (shell_pieces_with_engine).
Expected<EngineOutput> shell_with(const TriangleMesh& mesh, std::vector<layers::ShellPlan>& plans,
                                  const EngineRoute& route, const Context& ctx,
                                  const LayerField* stacks = nullptr);

/// Our header over an external engine's file: the route, `header` (what was curved) and the
/// settings forced on the engine's runs; shell_first_layer > 0: the shell route's, with its
/// core's first layer height (mm), and shell_pieces when the shells went between the core's
/// layers (engine_shell_settings). Lines end with '\n'.
std::string engine_header(const EngineRoute& route, const std::vector<std::string>& header,
                          double shell_first_layer, bool shell_pieces = false);

}  // namespace nonplanar
