// OrcaSlicer's JSON profiles (machine, process, filament), read as PrusaSlicer keys: the
// `inherits` chain resolved through the files around the profile, arrays taken as
// PrusaSlicer's per-extruder lists, Orca's names mapped (docs/orcaslicer-profiles.md).
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "core/file_bytes.hpp"
#include "core/text_tokens.hpp"
#include "nonplanar/config.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using Keys = std::vector<std::pair<std::string, std::string>>;

// OrcaSlicer's name → PrusaSlicer's, for the keys whose names differ. The rest (layer_height,
// nozzle_diameter, filament_diameter, travel_speed, skirt_distance, brim_width, gcode_flavor,
// use_relative_e_distances, machine_max_*, min/max_layer_height, …) are named alike.
const std::pair<const char*, const char*> kOrcaNames[] = {
    {"printable_area", "bed_shape"},
    {"printable_height", "max_print_height"},
    {"initial_layer_print_height", "first_layer_height"},
    {"wall_loops", "perimeters"},
    {"top_shell_layers", "top_solid_layers"},
    {"bottom_shell_layers", "bottom_solid_layers"},
    {"sparse_infill_density", "fill_density"},
    {"sparse_infill_pattern", "fill_pattern"},
    {"infill_direction", "fill_angle"},
    {"line_width", "extrusion_width"},
    {"outer_wall_line_width", "external_perimeter_extrusion_width"},
    {"inner_wall_line_width", "perimeter_extrusion_width"},
    {"sparse_infill_line_width", "infill_extrusion_width"},
    {"internal_solid_infill_line_width", "solid_infill_extrusion_width"},
    {"top_surface_line_width", "top_infill_extrusion_width"},
    {"initial_layer_line_width", "first_layer_extrusion_width"},
    {"outer_wall_speed", "external_perimeter_speed"},
    {"inner_wall_speed", "perimeter_speed"},
    {"sparse_infill_speed", "infill_speed"},
    {"internal_solid_infill_speed", "solid_infill_speed"},
    {"top_surface_speed", "top_solid_infill_speed"},
    {"initial_layer_speed", "first_layer_speed"},
    {"nozzle_temperature", "temperature"},
    {"nozzle_temperature_initial_layer", "first_layer_temperature"},
    {"hot_plate_temp", "bed_temperature"},
    {"hot_plate_temp_initial_layer", "first_layer_bed_temperature"},
    {"filament_flow_ratio", "extrusion_multiplier"},
    {"fan_max_speed", "max_fan_speed"},
    {"close_fan_the_first_x_layers", "disable_fan_first_layers"},
    {"retraction_length", "retract_length"},
    {"retraction_speed", "retract_speed"},
    {"deretraction_speed", "deretract_speed"},
    {"retraction_minimum_travel", "retract_before_travel"},
    {"z_hop", "retract_lift"},
    {"skirt_loops", "skirts"},
    {"enable_support", "support_material"},
    {"machine_start_gcode", "start_gcode"},
    {"machine_end_gcode", "end_gcode"},
    {"before_layer_change_gcode", "before_layer_gcode"},
    {"layer_change_gcode", "layer_gcode"},
    {"filament_start_gcode", "start_filament_gcode"},
    {"filament_end_gcode", "end_filament_gcode"},
};

// Orca widths in % are of the nozzle (PrusaSlicer's are of the layer height): given in mm.
bool is_orca_width(const std::string& orca_key) {
  return orca_key.size() > 11 && orca_key.compare(orca_key.size() - 10, 10, "line_width") == 0;
}

// Every file an `inherits` may name: the profile's folder and its vendor's machine, process
// and filament folders (OrcaSlicer's resources/profiles/VENDOR/{machine,process,filament}).
std::vector<fs::path> candidates(const fs::path& file) {
  std::vector<fs::path> out;
  std::set<fs::path> dirs{file.parent_path()};
  const fs::path vendor = file.parent_path().parent_path();
  for (const char* sub : {"machine", "process", "filament"}) dirs.insert(vendor / sub);
  std::error_code ec;
  for (const fs::path& d : dirs)
    for (const auto& e : fs::directory_iterator(d, ec))
      if (e.path().extension() == ".json") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

Expected<Json> read_json(const fs::path& file) {
  auto bytes = core::read_file_bytes(file, 16u << 20);
  if (!bytes) return Error{bytes.error().status, file.string() + ": " + bytes.error().message};
  Json j = Json::parse(bytes->view().begin(), bytes->view().end(), nullptr, false);
  if (j.is_discarded() || !j.is_object())
    return Error{Status::parse_error, file.string() + ": not a JSON object"};
  return j;
}

// The file whose "name" is `name`, among `files` (read once each, lazily).
Expected<fs::path> find_named(const std::vector<fs::path>& files, const std::string& name,
                              const fs::path& from) {
  // The usual layout names the file after the profile: try that first.
  for (const fs::path& f : files)
    if (f.stem() == name) return f;
  for (const fs::path& f : files) {
    auto j = read_json(f);
    if (j && j->value("name", "") == name) return f;
  }
  return Error{Status::invalid_argument,
               from.string() + ": inherits '" + name + "', which no profile beside it is named"};
}

// One value as PrusaSlicer writes it: an array of numbers or "AxB" points joined by commas
// (per-extruder lists, bed_shape), an array of text its first item, a bool 1 or 0.
Expected<std::string> as_text(const std::string& key, const Json& v, const fs::path& file) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return std::string(v.get<bool>() ? "1" : "0");
  if (v.is_number()) {
    if (!std::isfinite(v.get<double>()))
      return Error{Status::invalid_argument, file.string() + ": " + key + ": not finite"};
    return v.dump();
  }
  if (v.is_array()) {
    std::string joined;
    bool numeric = true;
    for (const Json& item : v) {
      auto t = as_text(key, item, file);
      if (!t) return t.error();
      const std::string s = *t;
      numeric =
          numeric && !s.empty() && s.find_first_not_of("0123456789.-+eEx% ") == std::string::npos;
      joined += (joined.empty() ? "" : ",") + s;
    }
    if (numeric || v.empty()) return joined;
    return as_text(key, v.front(), file);
  }
  return Error{Status::parse_error, file.string() + ": " + key + ": not a value OrcaSlicer writes"};
}

// The profile's own keys over its parents', parents first (a chain of at most 16).
Expected<std::map<std::string, std::string>> resolve(const fs::path& file, int depth) {
  if (depth > 16)
    return Error{Status::parse_error, file.string() + ": inherits too deep (a loop?)"};
  auto j = read_json(file);
  if (!j) return j.error();
  std::map<std::string, std::string> keys;
  const std::string parent = j->value("inherits", "");
  if (!parent.empty()) {
    auto pf = find_named(candidates(file), parent, file);
    if (!pf) return pf.error();
    auto pk = resolve(*pf, depth + 1);
    if (!pk) return pk.error();
    keys = std::move(*pk);
  }
  for (const auto& [k, v] : j->items()) {
    if (k == "inherits" || k == "from" || k == "instantiation" || k == "setting_id") continue;
    auto t = as_text(k, v, file);
    if (!t) return t.error();
    keys[k] = *t;
  }
  return keys;
}

}  // namespace

std::string prusaslicer_key(const std::string& orca_key) {
  for (const auto& [o, p] : kOrcaNames)
    if (orca_key == o) return p;
  return orca_key;
}

bool is_orca_profile(std::string_view json_text) {
  const Json j = Json::parse(json_text.begin(), json_text.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return false;
  const std::string type = j.value("type", "");
  return j.contains("inherits") || type == "machine" || type == "process" || type == "filament";
}

Expected<std::vector<std::pair<std::string, std::string>>> orca_profile_keys(
    const std::filesystem::path& file) {
  auto orca = resolve(file, 0);
  if (!orca) return orca.error();
  const std::string type = orca->count("type") ? orca->at("type") : "";
  const double nozzle =
      core::parse_double(orca->count("nozzle_diameter") ? orca->at("nozzle_diameter") : "")
          .value_or(0.4);
  Keys out;
  for (const auto& [k, v] : *orca) {
    if (k == "type" || k == "name") continue;
    const std::string key = prusaslicer_key(k);
    std::string value = v;
    if (k == "sparse_infill_pattern" && value == "zig-zag") value = "rectilinear";
    if (is_orca_width(k) && !value.empty() && value.back() == '%')
      if (auto pct = core::parse_double(value.substr(0, value.size() - 1)))
        value = std::to_string(*pct / 100.0 * nozzle);
    out.emplace_back(key, value);
    if (key != k) out.emplace_back(k, v);  // its own name too, for the profile's macros
  }
  // PrusaSlicer's record of the choice, as find_preset gives it.
  const char* id = type == "machine"   ? "printer_settings_id"
                   : type == "process" ? "print_settings_id"
                                       : "filament_settings_id";
  if (orca->count("name")) out.emplace_back(id, orca->at("name"));
  return out;
}

}  // namespace nonplanar
