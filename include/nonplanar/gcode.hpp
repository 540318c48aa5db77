// Stage gcode: the one G-code reader (into moves, for check and for mapping another slicer's
// G-code back) and a small stateful emitter turning toolpaths into G-code (no arcs), with the
// annotations PrusaSlicer's and OrcaSlicer's previews read, written atomically.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// One G0/G1 move with what it deposited.
struct PrintMove {
  Vec3 from{0, 0, 0}, to{0, 0, 0};
  double filament = 0;     ///< mm of filament pushed (negative: retraction)
  bool extruding = false;  ///< filament > 0 and the nozzle moved in XY
  std::string type;        ///< the ;TYPE: in force ("" before any)
  int layer = -1;          ///< ;LAYER_CHANGE count − 1
  double width = 0.45;     ///< ;WIDTH: in force
  int line = 0;            ///< 1-based line in the file (0 for moves made in memory)
};

/// Reads G-code strictly: G0/G1 (X Y Z E F), G92, G90/G91, M82/M83, the comments ;TYPE:,
/// ;WIDTH:, ;LAYER_CHANGE; other M-codes and motionless G-codes (G4, G10/G11, G21, G28, G29,
/// G80) pass. Arcs (G2/G3), inches (G20) and unknown G-codes are errors naming the line.
Expected<std::vector<PrintMove>> read_gcode_moves(std::string_view text);

/// The same moves straight from toolpaths (for the check before a file is written); when
/// `keep` is given, only the paths it accepts, called with each path and its layer (the
/// travel to the next kept path starts where the last kept one ended).
std::vector<PrintMove> moves_from_toolpaths(
    const std::vector<LayerToolpaths>& layers, const GcodeParams& g,
    const std::function<bool(const ExtrusionPath&, int layer)>& keep = nullptr);

/// Filament length (mm) per mm of path for a bead of width w, height h (Slic3r's model).
double filament_per_mm(double width, double height, const GcodeParams& g);

/// Are the profile's start and end G-code safe for make_gcode? Refused: a placeholder or
/// macro it cannot fill in ("{max_layer_z}", "[printer_model]", "{if …}"), outside comments;
/// a move off the bed; a line over 255 characters, or with a control byte, or a non-ASCII
/// byte outside its comment. Error: invalid_argument naming the key, the line and the bed.
Expected<bool> check_custom_gcode(const PrintConfig& c);

/// The whole program as text. Refuses (invalid_argument) a program that would leave the bed
/// (a skirt too wide, a part placed at the edge), and what check_custom_gcode refuses. `header`
/// lines are written as comments at the top.
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
