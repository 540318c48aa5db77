// Stage gcode: a small stateful emitter turning toolpaths into G-code (no arcs), with the
// annotations PrusaSlicer's and OrcaSlicer's previews read, written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// Filament length (mm) per mm of path for a bead of width w, height h (Slic3r's model).
double filament_per_mm(double width, double height, const GcodeParams& g);

/// The whole program as text. `header` lines are written as comments at the top.
Expected<std::string> make_gcode(const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                 const std::vector<std::string>& header, const Context& ctx);

/// make_gcode into a file, atomically (temporary file, then rename).
Expected<bool> write_gcode_file(const std::filesystem::path& file,
                                const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                const std::vector<std::string>& header, const Context& ctx);

/// A whole program already made (another engine's, mapped) into a file, atomically.
Expected<bool> write_gcode_text(const std::filesystem::path& file, const std::string& text,
                                const Context& ctx);

}  // namespace nonplanar
