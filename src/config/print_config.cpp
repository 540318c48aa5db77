// Setting values by PrusaSlicer key: the one place where settings are string-keyed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <sstream>
#include <tuple>

#include "core/text_tokens.hpp"
#include "nonplanar/config.hpp"

namespace nonplanar {
namespace {

Error bad(const std::string& key, const std::string& why) {
  return Error{Status::invalid_argument, key + ": " + why};
}

// First value of a comma-separated list (PrusaSlicer writes one per extruder).
std::string first_item(const std::string& v) {
  const auto c = v.find(',');
  std::string s = c == std::string::npos ? v : v.substr(0, c);
  s.erase(0, s.find_first_not_of(" \t"));
  s.erase(s.find_last_not_of(" \t\r") + 1);
  return s;
}

std::optional<double> number(const std::string& v) {
  return core::parse_double(first_item(v));
}

// "45" or "50%" (of `base`).
std::optional<double> number_or_percent(const std::string& v, double base) {
  std::string s = first_item(v);
  if (!s.empty() && s.back() == '%') {
    const auto d = core::parse_double(s.substr(0, s.size() - 1));
    return d ? std::optional<double>(*d / 100.0 * base) : std::nullopt;
  }
  return core::parse_double(s);
}

// PrusaSlicer stores G-code templates with \n escapes, some of them quoted.
std::string unescape(const std::string& v) {
  std::string out = core::unescape_ini(v);
  if (out.size() >= 2 && out.front() == '"' && out.back() == '"')
    out = out.substr(1, out.size() - 2);
  return out;
}

// The first string of a per-extruder list ("\"M900 K0\";\"…\""), its escapes undone.
std::string first_string(const std::string& v) {
  return core::ini_string_list(v).front();
}

// PrusaSlicer's rules, checked against prusa-slicer 2.5's own G-code header: a width in % is
// of the layer height (the first layer's, for first_layer_extrusion_width), not of the
// nozzle; a role's width of 0 means extrusion_width, and extrusion_width 0 means
// 1.125 × nozzle. (A 0.8 mm nozzle at 0.3 mm layers: 200 % is 0.60 mm, 0 is 0.90 mm.)
void resolve_relative(PrintConfig& c) {
  const RelativeSettings& r = c.relative;
  ToolpathParams& t = c.paths;
  auto of = [](const std::string& text, double base) {
    return number_or_percent(text, base).value_or(0.0);  // checked when it was set
  };
  // An empty text was never given: the field keeps its own value.
  auto set = [&](double& field, const std::string& text, double base) {
    if (!text.empty()) field = of(text, base);
  };
  const double lh = c.slice.layer_height;
  set(c.slice.first_layer_height, r.first_layer_height, lh);
  const double w0 = of(r.extrusion_width, lh);
  const double w = w0 > 0 ? w0 : 1.125 * t.nozzle_diameter;
  auto role = [&](const std::string& text, double base) {
    const double v = of(text, base);
    return v > 0 ? v : w;
  };
  t.extrusion_width = role(r.infill_width, lh);
  t.perimeter_width = role(r.perimeter_width, lh);
  t.external_perimeter_width = role(r.external_perimeter_width, lh);
  t.first_layer_width = role(r.first_layer_width, c.slice.first_layer_height);
  set(t.external_perimeter_speed, r.external_perimeter_speed, t.perimeter_speed);
  set(t.solid_infill_speed, r.solid_infill_speed, t.infill_speed);
  set(t.top_solid_infill_speed, r.top_solid_infill_speed, t.solid_infill_speed);
  set(t.first_layer_speed, r.first_layer_speed, t.perimeter_speed);
  if (!r.start_gcode_given) c.gcode.start_gcode = default_start_gcode(c.bed_min, c.bed_max);
}

// One key, without resolving the relative settings (set_config_value does that after it).
Expected<bool> set_value(PrintConfig& c, const std::string& key, const std::string& value) {
  ToolpathParams& t = c.paths;
  GcodeParams& g = c.gcode;
  auto num = [&](double& field) -> Expected<bool> {
    const auto d = number(value);
    if (!d) return bad(key, "'" + value + "' is not a finite number");
    field = *d;
    return true;
  };
  auto integer = [&](int& field) -> Expected<bool> {
    const auto d = number(value);
    if (!d || *d != std::floor(*d) || std::abs(*d) > 1e6)
      return bad(key, "'" + value + "' is not a whole number");
    field = static_cast<int>(*d);
    return true;
  };
  // A relative setting: checked now, resolved with the others after every key.
  auto rel = [&](std::string& text) -> Expected<bool> {
    const auto d = number_or_percent(value, 1.0);
    if (!d || *d < 0) return bad(key, "'" + value + "' is not a number >= 0 or a percentage");
    text = first_item(value);
    return true;
  };
  RelativeSettings& r = c.relative;
  if (key == "layer_height") return num(c.slice.layer_height);
  if (key == "first_layer_height") return rel(r.first_layer_height);
  if (key == "min_layer_height") return num(c.min_layer_height);
  if (key == "max_layer_height") return num(c.max_layer_height);
  if (key == "nozzle_diameter") return num(t.nozzle_diameter);
  if (key == "filament_diameter") return num(g.filament_diameter);
  if (key == "extrusion_multiplier") return num(g.extrusion_multiplier);
  if (key == "perimeters") return integer(t.perimeters);
  if (key == "top_solid_layers") return integer(t.top_solid_layers);
  if (key == "bottom_solid_layers") return integer(t.bottom_solid_layers);
  if (key == "fill_density") {
    const auto d = number_or_percent(value, 1.0);
    if (!d) return bad(key, "'" + value + "' is not a number or a percentage");
    // "0.2" and "20%" both mean 20 %; a bare number above 1 is a percentage too.
    t.fill_density = *d > 1.0 && value.find('%') == std::string::npos ? *d / 100.0 : *d;
    return true;
  }
  if (key == "fill_pattern") {
    const std::string v = first_item(value);
    if (v == "rectilinear" || v == "alignedrectilinear" || v == "line" || v == "monotonic")
      t.fill_pattern = InfillPattern::rectilinear;
    else if (v == "grid")
      t.fill_pattern = InfillPattern::grid;
    else {
      // PrusaSlicer's and OrcaSlicer's other patterns: printed as grid, with a note. Any
      // other word is a typo, and an error.
      static const char* const known[] = {
          "triangles",     "stars",        "cubic",        "concentric",        "honeycomb",
          "3dhoneycomb",   "gyroid",       "hilbertcurve", "archimedeanchords", "octagramspiral",
          "adaptivecubic", "supportcubic", "lightning",    "monotoniclines",    "crosshatch",
          "zig-zag",       "tri-hexagon",  "quartercubic"};
      if (std::find(std::begin(known), std::end(known), v) == std::end(known))
        return bad(key, "'" + v +
                            "' is not a fill pattern (rectilinear, grid, or one of "
                            "PrusaSlicer's, printed as grid)");
      t.fill_pattern = InfillPattern::grid;
      c.notes.push_back("fill_pattern " + v + " is not supported; using grid");
    }
    return true;
  }
  if (key == "fill_angle") return num(t.fill_angle);
  if (key == "skirts") return integer(t.skirts);
  if (key == "skirt_distance") return num(t.skirt_distance);
  if (key == "extrusion_width") return rel(r.extrusion_width);
  if (key == "perimeter_extrusion_width") return rel(r.perimeter_width);
  if (key == "infill_extrusion_width") return rel(r.infill_width);
  if (key == "external_perimeter_extrusion_width") return rel(r.external_perimeter_width);
  if (key == "first_layer_extrusion_width") return rel(r.first_layer_width);
  if (key == "perimeter_speed") return num(t.perimeter_speed);
  if (key == "external_perimeter_speed") return rel(r.external_perimeter_speed);
  if (key == "infill_speed") return num(t.infill_speed);
  if (key == "solid_infill_speed") return rel(r.solid_infill_speed);
  if (key == "top_solid_infill_speed") return rel(r.top_solid_infill_speed);
  if (key == "first_layer_speed") return rel(r.first_layer_speed);
  if (key == "travel_speed") return num(t.travel_speed);
  if (key == "temperature") return num(g.temperature);
  if (key == "first_layer_temperature") return num(g.first_layer_temperature);
  if (key == "bed_temperature") return num(g.bed_temperature);
  if (key == "first_layer_bed_temperature") return num(g.first_layer_bed_temperature);
  if (key == "retract_length") return num(g.retract_length);
  if (key == "retract_speed") return num(g.retract_speed);
  if (key == "deretract_speed") return num(g.deretract_speed);
  if (key == "retract_before_travel") return num(g.retract_before_travel);
  if (key == "retract_lift") return num(g.retract_lift);
  if (key == "max_fan_speed") return integer(g.fan_speed);
  if (key == "disable_fan_first_layers") return integer(g.disable_fan_first_layers);
  if (key == "use_relative_e_distances") {
    const std::string v = first_item(value);
    if (v != "0" && v != "1" && v != "true" && v != "false") return bad(key, "expected 0 or 1");
    g.relative_e = v == "1" || v == "true";
    return true;
  }
  if (key == "gcode_flavor") {
    const std::string v = first_item(value);
    if (v == "marlin2" || v == "marlin" || v == "marlinlegacy")
      g.flavor = GcodeFlavor::marlin2;
    else if (v == "klipper")
      g.flavor = GcodeFlavor::klipper;
    else if (v == "reprapfirmware" || v == "reprap" || v == "rrf")
      g.flavor = GcodeFlavor::reprapfirmware;
    else
      return bad(key, "'" + v + "' is not marlin2, klipper or reprapfirmware");
    return true;
  }
  if (read_by_print_stats(key)) {  // gcode/print_stats.cpp reads them from the profile
    std::size_t start = 0;
    for (;;) {
      const std::size_t comma = value.find(',', start);
      const std::string item =
          value.substr(start, comma == std::string::npos ? comma : comma - start);
      const auto v = core::parse_double(item);
      if (!v || !std::isfinite(*v) || *v < 0)
        return bad(key, "'" + item + "' is not a number >= 0 (or a list of them, one per mode)");
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    return true;
  }
  if (key == "gcode_label_objects") {  // 2.5's 0/1, 2.6's names; object_labels.hpp reads it
    const std::string v = first_item(value);
    if (v != "0" && v != "1" && v != "disabled" && v != "octoprint" && v != "firmware")
      return bad(key, "'" + v + "' is not 0, 1, disabled, octoprint or firmware");
    return true;
  }
  if (key == "start_gcode") {
    r.start_gcode_given = true;
    return g.start_gcode = unescape(value), true;
  }
  if (key == "end_gcode") return g.end_gcode = unescape(value), true;
  if (key == "before_layer_gcode") return g.before_layer_gcode = unescape(value), true;
  if (key == "layer_gcode") return g.layer_gcode = unescape(value), true;
  // Per-extruder lists ("\"M900 K0\";\"…\""): the first extruder's.
  if (key == "start_filament_gcode") return g.start_filament_gcode = first_string(value), true;
  if (key == "end_filament_gcode") return g.end_filament_gcode = first_string(value), true;
  if (key == "shell_layers") return integer(c.shell_layers);
  if (key == "shell_max_banded") return num(c.shell_max_banded);
  Toolhead& head = c.toolhead;
  if (key == "nozzle_tip_radius") return num(head.tip_radius);
  if (key == "nozzle_cone_angle") return num(head.cone_angle_deg);
  if (key == "heater_block_radius") return num(head.block_radius);
  if (key == "heater_block_clearance") return num(head.block_clearance);
  if (key == "toolhead_shape") {
    std::string v = unescape(value);
    v.erase(0, v.find_first_not_of(" \t"));
    v.erase(v.find_last_not_of(" \t\r") + 1);
    if (v.empty()) return head.shape.clear(), head.shape_name.clear(), true;  // the round head
    auto shape = load_toolhead_shape(v);
    if (!shape) return bad(key, shape.error().message);
    head.shape = std::move(*shape), head.shape_name = v;
    return true;
  }
  if (key == "bed_shape") {
    // "0x0,220x0,220x220,0x220": the bounding box of the corners.
    Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
    std::stringstream ss(value);
    std::string item;
    int n = 0;
    while (std::getline(ss, item, ',')) {
      const auto x = item.find('x');
      const auto a =
          x == std::string::npos ? std::nullopt : core::parse_double(first_item(item.substr(0, x)));
      const auto b = x == std::string::npos ? std::nullopt
                                            : core::parse_double(first_item(item.substr(x + 1)));
      if (!a || !b) return bad(key, "'" + item + "' is not XxY");
      lo = lo.cwiseMin(Vec2(*a, *b));
      hi = hi.cwiseMax(Vec2(*a, *b));
      ++n;
    }
    if (n < 3) return bad(key, "needs at least 3 corners");
    c.bed_min = lo;
    c.bed_max = hi;
    return true;
  }
  return false;
}

}  // namespace

bool read_by_print_stats(const std::string& key) {
  static const char* const prefixes[] = {"machine_max_feedrate_", "machine_max_acceleration_",
                                         "machine_max_jerk_"};
  for (const char* p : prefixes)
    if (key.rfind(p, 0) == 0 && key.size() > std::strlen(p)) return true;
  return key == "machine_min_extruding_rate" || key == "machine_min_travel_rate" ||
         key == "machine_max_junction_deviation" || key == "silent_mode" ||
         key == "remaining_times" || key == "filament_density" || key == "filament_cost";
}

Expected<bool> set_config_value(PrintConfig& c, const std::string& key, const std::string& value) {
  auto r = set_value(c, key, value);
  if (r && *r) resolve_relative(c);
  if (r) c.profile[key] = value;
  return r;
}

std::string default_start_gcode(const Vec2& bed_min, const Vec2& bed_max) {
  const double depth = bed_max.y() - bed_min.y();
  const double margin = std::min(20.0, 0.1 * depth);
  const double y0 = bed_min.y() + margin, y1 = bed_max.y() - margin;
  char purge[160];
  std::snprintf(purge, sizeof purge, "G1 X%g Y%g Z0.3 F6000\nG1 Y%g E%g F1200 ; purge line\n",
                bed_min.x() + 2.0, y0, y1, std::round(15.0 * (y1 - y0) / 180.0 * 100.0) / 100.0);
  return "G28 ; home all axes\nG1 Z5 F5000 ; lift nozzle\nG92 E0\n" + std::string(purge) +
         "G92 E0\n";
}

bool is_nonplanar_key(const std::string& key) {
  return key == "nozzle_tip_radius" || key == "nozzle_cone_angle" || key == "heater_block_radius" ||
         key == "heater_block_clearance" || key == "toolhead_shape" || key == "shell_layers" ||
         key == "shell_max_banded";
}

// Ranges: wide enough for any real printer, narrow enough that every value formats into a
// sane G-code line (travel_speed=1e10 once wrote F-2147483648, max_fan_speed=1000 M106 S2550).
Expected<void> validate_config(const PrintConfig& c) {
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  auto pos = [](double v, double hi) { return std::isfinite(v) && v > 0 && v <= hi; };
  const ToolpathParams& t = c.paths;
  const GcodeParams& g = c.gcode;
  const double d = t.nozzle_diameter;
  if (!pos(d, 3)) return bad("nozzle_diameter", "must be in (0, 3] mm");
  // 0.01 mm: below any printer's Z step that matters (stock profiles go down to 0.025), and
  // what keeps a "0.3%" first layer from slicing a part into 0.6 µm layers.
  if (!pos(c.slice.layer_height, d) || c.slice.layer_height < 0.01)
    return bad("layer_height", "must be 0.01 mm to the nozzle diameter");
  if (!pos(c.slice.first_layer_height, d) || c.slice.first_layer_height < 0.01)
    return bad("first_layer_height", "must be 0.01 mm to the nozzle diameter");
  for (const auto& [k, v] : {std::pair{"min_layer_height", c.min_layer_height},
                             {"max_layer_height", c.max_layer_height}})
    if (!std::isfinite(v) || v < 0) return bad(k, "must be a finite number >= 0 (0: automatic)");
  if (c.min_layer_height > 0 && c.max_layer_height > 0 && c.min_layer_height > c.max_layer_height)
    return bad("min_layer_height", "is above max_layer_height");
  if (c.max_layer_height > d) return bad("max_layer_height", "is larger than the nozzle diameter");
  if (!pos(g.filament_diameter, 5)) return bad("filament_diameter", "must be in (0, 5] mm");
  if (!pos(g.extrusion_multiplier, 5)) return bad("extrusion_multiplier", "must be in (0, 5]");
  const double lh = c.slice.layer_height, fh = c.slice.first_layer_height;
  for (const auto& [k, v, layer] :
       {std::tuple{"extrusion_width", t.extrusion_width, lh},
        {"perimeter_extrusion_width", t.perimeter_width, lh},
        {"external_perimeter_extrusion_width", t.external_perimeter_width, lh},
        {"first_layer_extrusion_width", t.first_layer_width, fh}}) {
    if (!pos(v, 1e3) || v < layer) return bad(k, "must be at least its layer's height");
    // Stock profiles use at least the nozzle's diameter; a quarter of it is already no line.
    if (v < 0.25 * d) return bad(k, "must be at least 25 % of the nozzle diameter");
    if (v >= 3 * d) return bad(k, "must be below 3 × the nozzle diameter (as PrusaSlicer)");
  }
  if (t.perimeters < 0 || t.perimeters > 100) return bad("perimeters", "must be 0 to 100");
  if (c.shell_layers < 0 || c.shell_layers > 20)
    return bad("shell_layers", "must be 0 (automatic) to 20");
  if (!in(c.shell_max_banded, 0, 1)) return bad("shell_max_banded", "must be 0 to 1");
  if (t.top_solid_layers < 0 || t.top_solid_layers > 1000 || t.bottom_solid_layers < 0 ||
      t.bottom_solid_layers > 1000)
    return bad("top_solid_layers/bottom_solid_layers", "must be 0 to 1000");
  if (!in(t.fill_density, 0, 1)) return bad("fill_density", "must be in 0 % … 100 %");
  if (!in(t.fill_angle, -360, 360)) return bad("fill_angle", "must be -360 to 360 degrees");
  if (t.skirts < 0 || t.skirts > 100) return bad("skirts", "must be 0 to 100");
  for (const auto& [k, v] : {std::pair{"perimeter_speed", t.perimeter_speed},
                             {"external_perimeter_speed", t.external_perimeter_speed},
                             {"infill_speed", t.infill_speed},
                             {"solid_infill_speed", t.solid_infill_speed},
                             {"top_solid_infill_speed", t.top_solid_infill_speed},
                             {"first_layer_speed", t.first_layer_speed},
                             {"travel_speed", t.travel_speed},
                             {"retract_speed", g.retract_speed}})
    if (!pos(v, 1000)) return bad(k, "must be a speed in (0, 1000] mm/s");
  if (!in(g.deretract_speed, 0, 1000))
    return bad("deretract_speed", "must be 0 (retract_speed) to 1000 mm/s");
  for (const auto& [k, v] : {std::pair{"temperature", g.temperature},
                             {"first_layer_temperature", g.first_layer_temperature},
                             {"bed_temperature", g.bed_temperature},
                             {"first_layer_bed_temperature", g.first_layer_bed_temperature}})
    if (!in(v, 0, 500)) return bad(k, "must be 0 to 500 °C");
  for (const auto& [k, v, hi] : {std::tuple{"retract_length", g.retract_length, 50.0},
                                 {"retract_before_travel", g.retract_before_travel, 1000.0},
                                 {"retract_lift", g.retract_lift, 50.0},
                                 {"skirt_distance", t.skirt_distance, 1000.0}})
    if (!in(v, 0, hi)) return bad(k, "must be 0 to " + std::to_string(int(hi)) + " mm");
  if (g.fan_speed < 0 || g.fan_speed > 100) return bad("max_fan_speed", "must be 0 to 100 %");
  if (g.disable_fan_first_layers < 0) return bad("disable_fan_first_layers", "must be 0 or more");
  const Toolhead& h = c.toolhead;
  if (!pos(h.tip_radius, 5)) return bad("nozzle_tip_radius", "must be in (0, 5] mm");
  if (!(h.cone_angle_deg >= 5 && h.cone_angle_deg <= 85))
    return bad("nozzle_cone_angle", "must be 5 to 85 degrees above horizontal");
  if (!pos(h.block_radius, 200) || h.block_radius <= h.tip_radius)
    return bad("heater_block_radius", "must be above nozzle_tip_radius and at most 200 mm");
  if (!pos(h.block_clearance, 200)) return bad("heater_block_clearance", "must be in (0, 200] mm");
  if (!c.bed_min.allFinite() || !c.bed_max.allFinite() || !(c.bed_max.x() > c.bed_min.x()) ||
      !(c.bed_max.y() > c.bed_min.y()))
    return bad("bed_shape", "is empty");
  if (c.bed_min.cwiseAbs().maxCoeff() > 1e5 || c.bed_max.cwiseAbs().maxCoeff() > 1e5)
    return bad("bed_shape", "corners must lie within 100 m of the origin");
  return {};
}

Expected<PrintConfig> parse_ini_config(std::string_view text, PrintConfig c) {
  std::size_t pos = 0;
  int line = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    std::string l(text.substr(pos, end - pos));
    pos = end + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.pop_back();
    const auto first = l.find_first_not_of(" \t");
    if (first == std::string::npos || l[first] == '#' || l[first] == ';' || l[first] == '[')
      continue;
    const auto eq = l.find('=');
    if (eq == std::string::npos)
      return Error{Status::parse_error, "line " + std::to_string(line) + ": expected key = value"};
    std::string key = l.substr(first, eq - first), value = l.substr(eq + 1);
    key.erase(key.find_last_not_of(" \t") + 1);
    value.erase(0, value.find_first_not_of(" \t"));
    auto r = set_config_value(c, key, value);
    if (!r)
      return Error{Status::parse_error, "line " + std::to_string(line) + ": " + r.error().message};
  }
  if (auto v = validate_config(c); !v) return v.error();
  return c;
}

}  // namespace nonplanar
