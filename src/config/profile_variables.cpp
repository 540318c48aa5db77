// The variables a profile's macros see before anything is printed.

#include <cmath>
#include <utility>

#include "nonplanar/macros.hpp"

namespace nonplanar {
namespace {

MacroValue number(double v) {
  return v == std::floor(v) && std::abs(v) < 1e9 ? MacroValue::integer(static_cast<long long>(v))
                                                 : MacroValue::real(v);
}

std::vector<MacroValue> pair(const Vec2& v) {
  return {MacroValue::real(v.x()), MacroValue::real(v.y())};
}

}  // namespace

MacroVariables profile_variables(const PrintConfig& c) {
  MacroVariables v;
  for (const auto& [k, t] : {std::pair{"printer_model", ""},
                             {"printer_notes", ""},
                             {"print_settings_id", ""},
                             {"printer_settings_id", ""},
                             {"input_filename_base", "model"},
                             {"gcode_flavor", "marlin2"}})
    v.set(k, MacroValue::text(t));
  v.set_vector("filament_settings_id", {MacroValue::text("")});
  v.set_vector("filament_type", {MacroValue::text("PLA")});
  v.set("z_offset", MacroValue::integer(0));
  v.set("max_print_height", MacroValue::integer(200));
  for (const auto& [k, raw] : c.profile) v.set_from_profile(k, raw);
  const GcodeParams& g = c.gcode;
  const ToolpathParams& t = c.paths;
  for (const auto& [k, x] : {std::pair{"first_layer_temperature", g.first_layer_temperature},
                             {"temperature", g.temperature},
                             {"bed_temperature", g.bed_temperature},
                             {"first_layer_bed_temperature", g.first_layer_bed_temperature},
                             {"nozzle_diameter", t.nozzle_diameter},
                             {"filament_diameter", g.filament_diameter},
                             {"retract_length", g.retract_length},
                             {"retract_speed", g.retract_speed},
                             {"retract_lift", g.retract_lift}})
    v.set_vector(k, {number(x)});
  for (const auto& [k, x] : {std::pair{"layer_height", c.slice.layer_height},
                             {"first_layer_height", c.slice.first_layer_height},
                             {"extrusion_width", t.extrusion_width},
                             {"travel_speed", t.travel_speed},
                             {"perimeter_speed", t.perimeter_speed}})
    v.set(k, number(x));
  v.set("use_relative_e_distances", MacroValue::integer(g.relative_e));
  for (const char* k : {"initial_extruder", "initial_tool", "current_extruder",
                        "current_object_idx", "total_toolchanges", "layer_num"})
    v.set(k, MacroValue::integer(0));
  for (const char* k : {"has_wipe_tower", "has_single_extruder_multi_material_priming"})
    v.set(k, MacroValue::boolean(false));
  v.set_vector("is_extruder_used", {MacroValue::boolean(true)});
  v.set("num_extruders", MacroValue::integer(1));
  v.set_vector("print_bed_min", pair(c.bed_min));
  v.set_vector("print_bed_max", pair(c.bed_max));
  v.set_vector("print_bed_size", pair(c.bed_max - c.bed_min));
  return v;
}

}  // namespace nonplanar
