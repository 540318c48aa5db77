// Stage gcode: the built-in engine's writer, turning toolpaths into G-code (no arcs): each
// layer built as steps (ProgramLayer, program.hpp) and written by the one writer (program/),
// with the annotations PrusaSlicer's and OrcaSlicer's previews read, written atomically.
// G-code is read by read_gcode_program (program.hpp).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "nonplanar/config.hpp"
#include "nonplanar/print_time.hpp"
#include "nonplanar/program.hpp"
#include "nonplanar/toolpaths.hpp"

namespace nonplanar {

/// Are the profile's start and end G-code safe for make_gcode? Refused: a placeholder or
/// macro it cannot fill in ("{max_layer_z}", "[printer_model]", "{if …}"), outside comments;
/// a move off the bed; a line over 255 characters, or with a control byte, or a non-ASCII
/// byte outside its comment. Error: invalid_argument naming the key, the line and the bed.
Expected<void> check_custom_gcode(const PrintConfig& c);

/// The whole program as text. Refuses (invalid_argument) a program that would leave the bed
/// (a skirt too wide, a part placed at the edge), and what check_custom_gcode refuses. `header`
/// lines are written as comments at the top.
Expected<std::string> make_gcode(const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                 const std::vector<std::string>& header, const Context& ctx);

/// The profile's machine limits (machine_max_* keys, their first value; PrusaSlicer's
/// defaults for the keys it does not set), for estimate_print_time.
/// `mode` 1 reads the keys' second values, the stealth ("silent") mode's, where given.
MachineLimits machine_limits(const PrintConfig& c, int mode = 0);

/// Does PrusaSlicer estimate a silent mode too for this profile: silent_mode = 1 on a Marlin
/// printer whose machine limits have a second (stealth) value?
bool silent_mode_estimate(const PrintConfig& c);

/// What with_print_stats measured: s, mm of filament, cm³, g (0 without filament_density).
struct PrintStats {
  double seconds = 0, filament_mm = 0, filament_cm3 = 0, filament_g = 0;
};

/// A program's statistics (read_gcode_program's reading): the time is estimate_print_time's
/// with machine_limits(c), whose per-line times go to `time` when given; filament is the net
/// E of every move; grams need the profile's filament_density.
PrintStats print_stats(const GcodeProgram& program, const PrintConfig& c,
                       PrintTime* time = nullptr);

/// The program with its statistics recomputed from its own moves, whoever wrote it: the
/// footer PrusaSlicer writes (filament used in mm, cm³ and g, filament cost when the profile
/// prices it, "; estimated printing time (normal mode) = 1h 2m 3s"; any such lines already
/// there are replaced, in place), and with remaining_times = 1 an "M73 P<percent> R<minutes
/// left>" at every layer change (the old M73 lines dropped); where silent_mode_estimate, also
/// "M73 Q<percent> S<minutes left>" and "; estimated printing time (silent mode) = …". Filament is
/// the net E of every move; the time is estimate_print_time's with machine_limits(c).
std::string with_print_stats(std::string_view gcode, const PrintConfig& c,
                             PrintStats* stats = nullptr);

/// with_print_stats in two steps, for a caller that wants the reading done beside other work
/// and the program changed in place, never held twice (the slicer's gate).
struct PrintStatsStamp {
  PrintStats stats;
  PrintTime normal, stealth;  ///< per-line times (stealth: where silent)
  bool silent = false, progress = false;
  std::size_t print_end = 0;  ///< the program's print_end (read_gcode_program)
  std::string footer;         ///< the footer's lines
};
/// Reads `gcode` (the time and filament) and prepares what with_print_stats writes.
PrintStatsStamp measure_print_stats(std::string_view gcode, const PrintConfig& c);
/// Writes what `m` measured of this very text into it, in place: the same text as
/// with_print_stats returns.
void stamp_print_stats(std::string& gcode, const PrintStatsStamp& m);

/// make_gcode into a file, atomically (temporary file, then rename).
Expected<void> write_gcode_file(const std::filesystem::path& file,
                                const std::vector<LayerToolpaths>& layers, const PrintConfig& c,
                                const std::vector<std::string>& header, const Context& ctx);

/// A whole program already made (another engine's, mapped) into a file, atomically.
Expected<void> write_gcode_text(const std::filesystem::path& file, const std::string& text,
                                const Context& ctx);

}  // namespace nonplanar
