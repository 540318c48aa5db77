// Another slicer as the planar engine (issue: libslic3r engine): PrusaSlicer's or OrcaSlicer's
// command line slices the normalised mesh with the user's own profile; the caller maps the
// G-code back (deform/map_foreign_gcode.cpp).
#pragma once

#include <string>
#include <vector>

#include "nonplanar/pipeline.hpp"

namespace nonplanar {

/// The settings forced on the engine's run, as "key = value" lines for the output's header.
std::vector<std::string> engine_forced_settings(const EngineParams& e, const PrintConfig& c);

/// Inputs: the engine, the mesh to slice (placed on our bed: its XY box centre stays where it
/// is), the print settings it must agree with (layer heights, bed centre). Output: the
/// G-code text the engine wrote. Runs the engine in a temporary folder (removed afterwards)
/// and stops it on cancellation. Errors: io_error (engine missing, failed: its last output
/// line), cancelled.
Expected<std::string> run_engine(const EngineParams& e, const TriangleMesh& mesh,
                                 const PrintConfig& c, const Context& ctx);

}  // namespace nonplanar
