// Print configuration: one typed settings struct per stage, built once from a JSON profile
// or a PrusaSlicer .ini, with command-line overrides (DESIGN.md §5). Millimetres, seconds
// (speeds in mm/s), degrees, °C. No global settings object: stages get their own struct.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "nonplanar/mesh.hpp"
#include "nonplanar/status.hpp"
#include "nonplanar/toolhead.hpp"

namespace nonplanar {

/// Inputs of slice_mesh.
struct SliceParams {
  double layer_height = 0.2;
  double first_layer_height = 0.2;
};

enum class InfillPattern { rectilinear, grid };

/// Inputs of make_toolpaths.
struct ToolpathParams {
  double nozzle_diameter = 0.4;
  double extrusion_width = 0.45;  ///< infill (and the default of the other widths)
  double perimeter_width = 0.45;  ///< inner perimeters
  double external_perimeter_width = 0.45;
  double first_layer_width = 0.5;  ///< every extrusion of the first layer
  int perimeters = 2;
  int top_solid_layers = 5;
  int bottom_solid_layers = 4;
  double fill_density = 0.2;  ///< 0 … 1
  InfillPattern fill_pattern = InfillPattern::rectilinear;
  double fill_angle = 45;  ///< degrees; alternates ±90 per layer
  int skirts = 1;
  double skirt_distance = 6;
  // Speeds (mm/s).
  double perimeter_speed = 45, external_perimeter_speed = 25, infill_speed = 80,
         solid_infill_speed = 60, top_solid_infill_speed = 40, first_layer_speed = 20,
         travel_speed = 150;
};

enum class GcodeFlavor { marlin2, klipper, reprapfirmware };

/// Inputs of write_gcode.
struct GcodeParams {
  GcodeFlavor flavor = GcodeFlavor::marlin2;
  bool relative_e = false;
  double filament_diameter = 1.75;
  double extrusion_multiplier = 1.0;
  double temperature = 210, first_layer_temperature = 215;
  double bed_temperature = 60, first_layer_bed_temperature = 60;
  double retract_length = 0.8, retract_speed = 35, deretract_speed = 0;  ///< 0: retract_speed
  double retract_before_travel = 2.0;  ///< travels shorter than this are not retracted
  double retract_lift = 0.0;           ///< z-hop
  int fan_speed = 100;                 ///< percent, from layer disable_fan_first_layers on
  int disable_fan_first_layers = 1;
  std::string start_gcode =
      "G28 ; home all axes\nG1 Z5 F5000 ; lift nozzle\nG92 E0\n"
      "G1 X2 Y20 Z0.3 F6000\nG1 Y200 E15 F1200 ; purge line\nG92 E0\n";
  std::string end_gcode =
      "M104 S0 ; heater off\nM140 S0 ; bed off\nM107\nG91\nG1 Z10 F600\nG90\nM84\n";
  /// At each layer change, before and after the move to the new layer (PrusaSlicer's
  /// before_layer_gcode and layer_gcode), and around the print for the first extruder's
  /// filament. Every block is a template of PrusaSlicer's macro language (macros.hpp).
  std::string before_layer_gcode, layer_gcode, start_filament_gcode, end_filament_gcode;
  /// The object's name in its labels (gcode_label_objects): the model's file name.
  std::string object_name = "part";
  /// A plate's objects, for their labels (ExtrusionPath::object indexes them); with fewer
  /// than two, the one object is object_name.
  std::vector<PlateObject> objects;
};

/// Settings PrusaSlicer states relative to others, as written: "150%" (widths: of the layer
/// height, the first layer's for the first layer's width; first_layer_height: of the layer
/// height; speeds: of another speed) or 0 for a width (automatic: 1.125 × nozzle for
/// extrusion_width, and extrusion_width for the other widths). Every set_config_value() resolves
/// them all again, so the result does not depend on the order of the keys (`prusa-slicer --save`
/// writes them alphabetically, nozzle_diameter after the widths).
/// An empty text was not given, and its field keeps its default. The widths always follow
/// their rule: by default automatic, and 250 % of the first layer (0.5 mm at 0.2 mm).
struct RelativeSettings {
  std::string first_layer_height;
  std::string extrusion_width = "0", perimeter_width = "0", infill_width = "0",
              external_perimeter_width = "0", first_layer_width = "250%";
  std::string external_perimeter_speed, solid_infill_speed, top_solid_infill_speed,
      first_layer_speed;
  bool start_gcode_given = false;  ///< else the default start G-code is made for the bed
};

/// Everything a print needs.
struct PrintConfig {
  Vec2 bed_min{0, 0}, bed_max{220, 220};  ///< bed_shape's bounding box
  /// Thinnest and thickest layer the printer prints well, h_min and h_max of the curved layers
  /// (PrusaSlicer's min_layer_height / max_layer_height, mm). 0 = automatic:
  /// h_min = min(0.1, layer_height),
  /// h_max = min(nozzle, max(1.5 layer_height, min(0.75 nozzle, 0.3))).
  double min_layer_height = 0, max_layer_height = 0;
  /// Curved layers of a shell over a planar core (`shell_layers`, ours; 0 = automatic: 0.4 mm
  /// of them, at least 2). The core prints its own top solid layers under the shell's lowest.
  int shell_layers = 0;
  /// The largest share of a shell's curved top it may print in bands beside what stands above
  /// it (`shell_max_banded`, ours, 0 to 1): past it the shell is refused, as its bands cost
  /// print time (1: never refused for that).
  double shell_max_banded = 1.0;
  SliceParams slice;
  ToolpathParams paths;
  GcodeParams gcode;
  Toolhead toolhead;          ///< nozzle cone, heater block, the rest of the head (toolhead.hpp)
  RelativeSettings relative;  ///< what the relative fields above were resolved from
  std::vector<std::string> notes;  ///< settings that were read but adapted (shown as warnings)
  /// Every key set, as written (PrusaSlicer's text, escapes intact), known to us or not: what
  /// the custom G-code's macros read, and what another engine is given.
  std::map<std::string, std::string> profile;
  Vec2 bed_center() const { return 0.5 * (bed_min + bed_max); }
};

/// The start G-code used when a profile gives none: home, heat (the writer waits), and a
/// purge line along the bed's left edge, 2 mm in, from 10 % to 90 % of its depth (at most
/// 20 mm from either end). For the default 220 × 220 bed: X2, Y20 → Y200, 15 mm of filament.
std::string default_start_gcode(const Vec2& bed_min, const Vec2& bed_max);

/// Sets one setting by its PrusaSlicer key (e.g. "layer_height", "fill_density" = "20%",
/// "bed_shape" = "0x0,220x0,220x220,0x220", "gcode_flavor" = "marlin2"). Unknown keys are
/// ignored (returns false); a bad value is an invalid_argument error naming the key.
Expected<bool> set_config_value(PrintConfig& c, const std::string& key, const std::string& value);

/// A head shape (docs/toolhead.md): JSON text, or a file. `toolhead_shape` in a profile names a
/// file, or a head shipped in toolheads/ by its name (`prusa-mk3s`). Errors name the problem
/// (and the file).
Expected<std::vector<ToolheadSlice>> parse_toolhead_shape(std::string_view json);
Expected<std::vector<ToolheadSlice>> load_toolhead_shape(const std::string& file_or_name);

/// Is `key` one of ours rather than PrusaSlicer's (the toolhead's keys)? Such keys are not
/// passed on to another slicer.
bool is_nonplanar_key(const std::string& key);

/// Checks ranges (finite, positive heights, density in [0, 1], ...). Error names the key.
Expected<void> validate_config(const PrintConfig& c);

/// Loads a JSON profile ({"layer_height": 0.2, ...}, keys as above) or a PrusaSlicer .ini
/// (key = value lines) over `base` (the defaults, or the profiles loaded before it: a
/// printer, a print and a filament file, as PrusaSlicer exports them one by one).
/// Error: "FILE: line N: problem".
Expected<PrintConfig> load_config(const std::filesystem::path& file, PrintConfig base = {});

/// The settings block PrusaSlicer writes at the end of its G-code ("; prusaslicer_config =
/// begin" … "= end", one "; key = value" per line), or OrcaSlicer's ("; CONFIG_BLOCK_START"
/// … "_END", its keys renamed by prusaslicer_key), as .ini text for parse_ini_config; empty
/// when the file has none (our built-in engine's).
std::string gcode_config_block(std::string_view gcode);

/// The keys the time and filament figures read from the profile (they have no field of their
/// own): PrusaSlicer's machine limits, junction deviation, stealth mode and M73 switches, and
/// the filament's density and cost.
bool read_by_print_stats(const std::string& key);

/// Adds to the settings block of `gcode` (gcode_config_block's) each key of `c.profile` that
/// read_by_print_stats names and the block lacks, as "; key = value" before the block's end
/// line. An engine leaves out what it does not know (PrusaSlicer 2.5:
/// machine_max_junction_deviation), and `check` would then time the file without it. Returns
/// how many lines were added (none without a block).
std::size_t complete_config_block(std::string& gcode, const PrintConfig& c);

/// OrcaSlicer's profiles (docs/orcaslicer-profiles.md). Is this JSON one (a "type" of
/// machine, process or filament, or an "inherits")?
bool is_orca_profile(std::string_view json_text);
/// PrusaSlicer's name for an OrcaSlicer key (wall_loops → perimeters); other keys unchanged.
std::string prusaslicer_key(const std::string& orca_key);
/// The profile in `file` with its `inherits` chain resolved (parents looked for beside it and
/// in its vendor's machine, process and filament folders, by file name or "name"), as
/// PrusaSlicer keys and values: arrays of numbers joined with commas, of text their first
/// item; widths in % (of the nozzle, in OrcaSlicer) in mm. Keys we do not use are kept, for
/// the macros and another engine. Errors name the file.
Expected<std::vector<std::pair<std::string, std::string>>> orca_profile_keys(
    const std::filesystem::path& file);

/// Parses .ini text / JSON text over `base` (for tests and fuzzing).
Expected<PrintConfig> parse_ini_config(std::string_view text, PrintConfig base = {});
Expected<PrintConfig> parse_json_config(std::string_view text, PrintConfig base = {});

}  // namespace nonplanar
