// Profiles read as PrusaSlicer reads them, and settings kept in ranges that print.
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

#include "nonplanar/config.hpp"
#include "nonplanar/pipeline.hpp"

namespace nonplanar {
namespace {

// The keys of a 0.8 mm nozzle profile in the alphabetical order `prusa-slicer --save`
// writes them: every width and the first layer come before the layer height and nozzle.
const char* kSaved08 =
    "external_perimeter_extrusion_width = 200%\n"
    "extrusion_width = 0.45\n"
    "first_layer_extrusion_width = 150%\n"
    "first_layer_height = 0.45\n"
    "infill_extrusion_width = 0\n"
    "layer_height = 0.3\n"
    "nozzle_diameter = 0.8\n"
    "perimeter_extrusion_width = 0\n";

std::string reversed_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  std::reverse(lines.begin(), lines.end());
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// The figures are prusa-slicer 2.5's own, from the header of the G-code it wrote with this
// file: "external perimeters extrusion width = 0.60mm" (200 % of the 0.3 mm layer), "first
// layer extrusion width = 0.67mm" (150 % of 0.45), perimeters and infill 0.45 (0 means
// extrusion_width). Before, the widths were resolved as each line came: 0.45 was
// overwritten by the 0 of perimeter_extrusion_width (auto against a 0.4 nozzle).
TEST(Config, SavedProfileResolvesAfterEverythingIsRead) {
  for (const std::string& text : {std::string(kSaved08), reversed_lines(kSaved08)}) {
    auto c = parse_ini_config(text);
    ASSERT_TRUE(c) << c.error().message;
    EXPECT_DOUBLE_EQ(c->paths.nozzle_diameter, 0.8);
    EXPECT_DOUBLE_EQ(c->slice.first_layer_height, 0.45);
    EXPECT_NEAR(c->paths.external_perimeter_width, 0.60, 1e-12);
    EXPECT_NEAR(c->paths.first_layer_width, 0.675, 1e-12);
    EXPECT_NEAR(c->paths.perimeter_width, 0.45, 1e-12);
    EXPECT_NEAR(c->paths.extrusion_width, 0.45, 1e-12);
  }
}

// prusa-slicer 2.5 with extrusion_width = 0 and infill_extrusion_width = 120% on a 0.8 mm
// nozzle at 0.3 mm: perimeters 0.90 (1.125 × nozzle), infill 0.36 (120 % of the layer).
TEST(Config, AutomaticWidthsFollowTheNozzleInAnyOrder) {
  const std::string text =
      "infill_extrusion_width = 120%\nextrusion_width = 0\nlayer_height = 0.3\n"
      "nozzle_diameter = 0.8\nfirst_layer_height = 150%\n";
  for (const std::string& t : {text, reversed_lines(text)}) {
    auto c = parse_ini_config(t);
    ASSERT_TRUE(c) << c.error().message;
    EXPECT_NEAR(c->paths.perimeter_width, 0.90, 1e-12);
    EXPECT_NEAR(c->paths.external_perimeter_width, 0.90, 1e-12);
    EXPECT_NEAR(c->paths.extrusion_width, 0.36, 1e-12);
    EXPECT_NEAR(c->slice.first_layer_height, 0.45, 1e-12);  // % of the layer, not of 0.2
  }
  // JSON keys come sorted too; a 0.6 mm nozzle alone widens every default width.
  auto j = parse_json_config(R"({"nozzle_diameter": 0.6})");
  ASSERT_TRUE(j);
  EXPECT_NEAR(j->paths.extrusion_width, 0.675, 1e-12);
  EXPECT_NEAR(j->paths.perimeter_width, 0.675, 1e-12);
  PrintConfig d;  // the defaults, resolved, are what they always were
  EXPECT_TRUE(set_config_value(d, "layer_height", "0.2").value());
  EXPECT_DOUBLE_EQ(d.paths.extrusion_width, 0.45);
  EXPECT_DOUBLE_EQ(d.paths.external_perimeter_width, 0.45);
  EXPECT_DOUBLE_EQ(d.paths.first_layer_width, 0.5);
  EXPECT_DOUBLE_EQ(d.slice.first_layer_height, 0.2);
  EXPECT_EQ(d.gcode.start_gcode, GcodeParams().start_gcode);
}

TEST(Config, SpeedsGivenInPercentFollowTheirBase) {
  auto c = parse_ini_config(
      "top_solid_infill_speed = 50%\nsolid_infill_speed = 50%\ninfill_speed = 200\n"
      "first_layer_speed = 50%\nperimeter_speed = 60\nexternal_perimeter_speed = 50%\n");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_DOUBLE_EQ(c->paths.solid_infill_speed, 100);
  EXPECT_DOUBLE_EQ(c->paths.top_solid_infill_speed, 50);
  EXPECT_DOUBLE_EQ(c->paths.external_perimeter_speed, 30);
  EXPECT_DOUBLE_EQ(c->paths.first_layer_speed, 30);
}

// Hostile-input #10: every one of these once reached the G-code (F-2147483648, M106 S2550,
// a 5 mm first layer, lines cut at 255 characters, a skirt 457 m off the bed).
TEST(Config, EverySettingHasARange) {
  const std::pair<const char*, const char*> cases[] = {
      {"travel_speed", "1e10"},
      {"max_fan_speed", "1000"},
      {"first_layer_height", "5"},
      {"extrusion_multiplier", "1e300"},
      {"skirts", "1000000"},
      {"skirt_distance", "1e9"},
      {"nozzle_diameter", "40"},
      {"filament_diameter", "100"},
      {"retract_length", "1e6"},
      {"retract_lift", "1e6"},
      {"perimeter_speed", "5000"},
      {"deretract_speed", "1e9"},
      {"extrusion_width", "5"},
      {"fill_angle", "1e9"},
      {"bed_shape", "0x0,1e9x0,1e9x1e9"},
      {"top_solid_layers", "100000"},
      {"first_layer_extrusion_width", "1000%"},
      {"first_layer_height", "0.3%"},  // fuzz_settings: 0.6 µm layers ordered for minutes
      {"layer_height", "0.005"},
      {"shell_layers", "21"},
      {"shell_layers", "-1"},
      {"shell_layers", "2.5"},
      {"shell_max_banded", "1.5"},
      {"shell_max_banded", "-0.1"},
  };
  for (const auto& [key, value] : cases) {
    PrintConfig c;
    auto set = set_config_value(c, key, value);
    const auto valid = set ? validate_config(c) : Expected<void>(set.error());
    ASSERT_FALSE(valid) << key << " = " << value;
    EXPECT_NE(valid.error().message.find(key), std::string::npos) << valid.error().message;
  }
  PrintConfig thin;  // thinner than its layer is caught first; a fine layer lets this through
  ASSERT_TRUE(set_config_value(thin, "layer_height", "0.05"));
  ASSERT_TRUE(set_config_value(thin, "extrusion_width", "0.08"));
  auto r = validate_config(thin);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "extrusion_width: must be at least 25 % of the nozzle diameter");
  ASSERT_TRUE(set_config_value(thin, "extrusion_width", "0.1"));
  EXPECT_TRUE(validate_config(thin));
}

// #16 item 2: the keys the time estimate reads from the profile are settings of their own, so
// `--set machine_max_acceleration_extruding=500` is taken (it was "unknown setting"), takes
// effect, and a bad value is refused naming the key.
TEST(Config, MachineLimitsAreSettingsTheEstimateReads) {
  PrintConfig c;
  for (const char* key :
       {"machine_max_acceleration_extruding", "machine_max_jerk_x", "machine_max_feedrate_e",
        "machine_min_travel_rate", "silent_mode", "remaining_times", "filament_density",
        "filament_cost", "machine_max_junction_deviation"}) {
    auto r = set_config_value(c, key, "1");
    ASSERT_TRUE(r) << key;
    EXPECT_TRUE(*r) << key;
  }
  ASSERT_TRUE(set_config_value(c, "machine_max_acceleration_extruding", "500,960"));
  EXPECT_EQ(machine_limits(c).accel_extruding, 500);
  EXPECT_EQ(machine_limits(c, 1).accel_extruding, 960);
  ASSERT_TRUE(set_config_value(c, "machine_max_junction_deviation", "0.013,0.02"));
  EXPECT_EQ(machine_limits(c).junction_deviation, 0.013);
  EXPECT_EQ(machine_limits(c, 1).junction_deviation, 0.02);
  auto bad = set_config_value(c, "machine_max_jerk_y", "8,fast");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("machine_max_jerk_y: 'fast' is not a number"),
            std::string::npos)
      << bad.error().message;
  EXPECT_FALSE(*set_config_value(c, "machine_max_jerk_", "3"));  // no axis: not ours
}

// An engine leaves out of its settings block what it does not know (PrusaSlicer 2.5: junction
// deviation): the file then gets the user's value, so `check` times it as its footer did.
TEST(Config, TheSettingsBlockGetsTheTimingKeysTheEngineLeftOut) {
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "machine_max_junction_deviation", "0.02"));
  ASSERT_TRUE(set_config_value(c, "machine_max_jerk_x", "8"));
  ASSERT_TRUE(set_config_value(c, "layer_height", "0.15"));  // not a timing key
  const std::string head = "G1 X1 E1\n; prusaslicer_config = begin\n; layer_height = 0.2\n";
  std::string g = head + "; machine_max_jerk_x = 10\n; prusaslicer_config = end\n";
  EXPECT_EQ(complete_config_block(g, c), 1u);
  EXPECT_EQ(g, head +
                   "; machine_max_jerk_x = 10\n; machine_max_junction_deviation = 0.02\n"
                   "; prusaslicer_config = end\n");
  auto read = parse_ini_config(gcode_config_block(g));
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(machine_limits(*read).junction_deviation, 0.02);
  EXPECT_EQ(machine_limits(*read).jerk_x, 10);  // the engine's own value stays
  EXPECT_EQ(complete_config_block(g, c), 0u);   // once only
  std::string none = "G1 X1 E1\n";  // no block (the built-in engine's): nothing to complete
  EXPECT_EQ(complete_config_block(none, c), 0u);
  EXPECT_EQ(none, "G1 X1 E1\n");
}

TEST(Config, UnknownFillPatternIsAnErrorAndPrusaSlicersAreNoted) {
  PrintConfig c;
  auto typo = set_config_value(c, "fill_pattern", "nosuchpattern");
  ASSERT_FALSE(typo);
  EXPECT_NE(typo.error().message.find("fill_pattern: 'nosuchpattern'"), std::string::npos);
  ASSERT_TRUE(set_config_value(c, "fill_pattern", "gyroid"));
  EXPECT_EQ(c.paths.fill_pattern, InfillPattern::grid);
  ASSERT_EQ(c.notes.size(), 1u);
  EXPECT_NE(c.notes[0].find("gyroid"), std::string::npos);
}

TEST(Config, DefaultPurgeLineFitsTheBed) {
  EXPECT_EQ(default_start_gcode({0, 0}, {220, 220}), GcodeParams().start_gcode);
  auto c = parse_ini_config("bed_shape = 0x0,180x0,180x180,0x180\n");
  ASSERT_TRUE(c);
  EXPECT_NE(c->gcode.start_gcode.find("G1 X2 Y18 Z0.3"), std::string::npos);
  EXPECT_NE(c->gcode.start_gcode.find("G1 Y162 E12"), std::string::npos);
  auto off = parse_ini_config("bed_shape = -100x-50,100x-50,100x150,-100x150\n");
  ASSERT_TRUE(off);
  EXPECT_NE(off->gcode.start_gcode.find("G1 X-98 Y-30 Z0.3"), std::string::npos);
  EXPECT_NE(off->gcode.start_gcode.find("G1 Y130 E13.33"), std::string::npos);
  // A start G-code of the profile's own is kept, whatever comes after it.
  auto own = parse_ini_config("start_gcode = G28\\nG1 X5 Y5\nbed_shape = 0x0,180x0,180x180\n");
  ASSERT_TRUE(own);
  EXPECT_EQ(own->gcode.start_gcode, "G28\nG1 X5 Y5");
}

// Hostile-input #16: layer_height 0.3 on a 0.4 mm nozzle made h_max 0.45, and curved layers
// of 0.431 mm, where max_layer_height = 0.45 given by hand is refused.
TEST(Config, AutomaticLayerLimitsStayWithinTheNozzle) {
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "layer_height", "0.3"));
  EXPECT_DOUBLE_EQ(make_job(c, 30).layers.max_layer_height, 0.4);
  ASSERT_TRUE(set_config_value(c, "layer_height", "0.2"));
  EXPECT_DOUBLE_EQ(make_job(c, 30).layers.max_layer_height, 0.3);
  ASSERT_TRUE(set_config_value(c, "nozzle_diameter", "0.25"));
  ASSERT_TRUE(set_config_value(c, "layer_height", "0.15"));
  EXPECT_DOUBLE_EQ(make_job(c, 30).layers.max_layer_height, 0.225);
}

}  // namespace
}  // namespace nonplanar
