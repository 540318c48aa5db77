// Stage engine: what slices the normalised mesh. The built-in engine (slice, toolpaths, then
// the paths mapped back), or another slicer's command line (PrusaSlicer, OrcaSlicer) with the
// user's own profile, its G-code mapped back (deform/map_foreign_gcode).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace nonplanar {

/// The planar engine that slices the (normalised) mesh.
enum class Engine { builtin, prusaslicer, orcaslicer };

struct EngineParams {
  Engine engine = Engine::builtin;
  std::string path;       ///< its executable; empty: prusa-slicer / orca-slicer on PATH
  std::string config;     ///< PrusaSlicer: a profile .ini (--load); OrcaSlicer: --load-settings
  std::string filaments;  ///< OrcaSlicer: --load-filaments
  /// Settings the user overrode (PrusaSlicer keys and values), passed on to PrusaSlicer.
  std::vector<std::pair<std::string, std::string>> overrides;
};

}  // namespace nonplanar
