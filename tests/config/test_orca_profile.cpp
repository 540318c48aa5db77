// OrcaSlicer's JSON profiles: a machine, process and filament laid out as OrcaSlicer ships
// them (resources/profiles/VENDOR/{machine,process,filament}), each inheriting from an
// abstract parent, read as PrusaSlicer keys. The files are written here, in OrcaSlicer's
// format, with values of our choosing.
#include <gtest/gtest.h>

#include <filesystem>

#include "nonplanar/config.hpp"
#include "nonplanar/gcode.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

namespace fs = std::filesystem;

fs::path orca_vendor() {
  const fs::path v = test::temp_dir("orca_vendor") / "Voron";
  fs::create_directories(v / "machine");
  fs::create_directories(v / "process");
  fs::create_directories(v / "filament");
  test::write_bytes(v / "machine" / "fdm_machine_common.json", R"({
    "type": "machine", "name": "fdm_machine_common", "from": "system", "instantiation": "false",
    "gcode_flavor": "marlin2", "nozzle_diameter": ["0.4"], "retraction_length": ["0.8"],
    "machine_max_acceleration_extruding": ["20000", "20000"], "z_hop": ["0.4"],
    "printable_area": ["0x0", "220x0", "220x220", "0x220"]})");
  test::write_bytes(v / "machine" / "fdm_klipper_common.json", R"({
    "type": "machine", "name": "fdm_klipper_common", "inherits": "fdm_machine_common",
    "from": "system", "instantiation": "false", "gcode_flavor": "klipper",
    "machine_start_gcode": "PRINT_START EXTRUDER=[nozzle_temperature_initial_layer] BED=[first_layer_bed_temperature]\nG92 E0\n",
    "layer_change_gcode": "SET_PRINT_STATS_INFO CURRENT_LAYER={layer_num + 1}"})");
  // Named differently from its file: found by "name".
  test::write_bytes(v / "machine" / "voron_24_250.json", R"({
    "type": "machine", "setting_id": "GM_VORON_002", "name": "Voron 2.4 250 0.4 nozzle",
    "from": "system", "instantiation": "true", "inherits": "fdm_klipper_common",
    "nozzle_diameter": ["0.4"], "printable_area": ["0x0", "250x0", "250x250", "0x250"],
    "printable_height": "225"})");
  test::write_bytes(v / "process" / "fdm_process_common.json", R"({
    "type": "process", "name": "fdm_process_common", "wall_loops": "2",
    "top_shell_layers": "4", "sparse_infill_density": "20%", "layer_height": "0.2",
    "initial_layer_print_height": "0.25"})");
  test::write_bytes(v / "process" / "0.20mm Standard @Voron.json", R"({
    "type": "process", "name": "0.20mm Standard @Voron", "inherits": "fdm_process_common",
    "wall_loops": "3", "sparse_infill_density": "15%", "sparse_infill_pattern": "zig-zag",
    "outer_wall_line_width": "110%", "outer_wall_speed": "120", "brim_width": "0"})");
  test::write_bytes(v / "filament" / "Voron Generic PLA.json", R"({
    "type": "filament", "name": "Voron Generic PLA", "nozzle_temperature": ["210"],
    "nozzle_temperature_initial_layer": ["215"], "hot_plate_temp": ["60"],
    "hot_plate_temp_initial_layer": ["65"], "filament_flow_ratio": ["0.98"],
    "filament_diameter": ["1.75"], "fan_max_speed": ["80"]})");
  return v;
}

TEST(OrcaProfile, ChainsResolveAndKeysMapToPrusaSlicers) {
  const fs::path v = orca_vendor();
  auto m = load_config(v / "machine" / "voron_24_250.json");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->bed_max, Vec2(250, 250));             // the child's printable_area
  EXPECT_EQ(m->gcode.flavor, GcodeFlavor::klipper);  // the parent's over the grandparent's
  EXPECT_DOUBLE_EQ(m->gcode.retract_length, 0.8);    // the grandparent's
  EXPECT_DOUBLE_EQ(m->gcode.retract_lift, 0.4);      // z_hop
  EXPECT_EQ(m->profile.at("machine_max_acceleration_extruding"), "20000,20000");
  EXPECT_EQ(m->profile.at("printer_settings_id"), "Voron 2.4 250 0.4 nozzle");
  auto p = load_config(v / "process" / "0.20mm Standard @Voron.json", *m);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_EQ(p->paths.perimeters, 3);
  EXPECT_EQ(p->paths.top_solid_layers, 4);
  EXPECT_NEAR(p->paths.fill_density, 0.15, 1e-12);
  EXPECT_EQ(p->paths.fill_pattern, InfillPattern::rectilinear);  // zig-zag
  EXPECT_NEAR(p->paths.external_perimeter_width, 0.44, 1e-9);    // 110 % of the 0.4 nozzle
  EXPECT_NEAR(p->paths.external_perimeter_speed, 120, 1e-12);
  EXPECT_NEAR(p->slice.first_layer_height, 0.25, 1e-12);
  auto f = load_config(v / "filament" / "Voron Generic PLA.json", *p);
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_DOUBLE_EQ(f->gcode.temperature, 210);
  EXPECT_DOUBLE_EQ(f->gcode.first_layer_temperature, 215);
  EXPECT_DOUBLE_EQ(f->gcode.bed_temperature, 60);
  EXPECT_DOUBLE_EQ(f->gcode.first_layer_bed_temperature, 65);
  EXPECT_DOUBLE_EQ(f->gcode.extrusion_multiplier, 0.98);
  EXPECT_EQ(f->gcode.fan_speed, 80);
  // The start block reads Orca's own names ([nozzle_temperature_initial_layer]).
  EXPECT_TRUE(check_custom_gcode(*f));
  // A flat JSON with Orca's names is read too, not ignored.
  auto flat = parse_json_config(R"({"wall_loops": 4, "nozzle_temperature": 230})");
  ASSERT_TRUE(flat) << flat.error().message;
  EXPECT_EQ(flat->paths.perimeters, 4);
  EXPECT_DOUBLE_EQ(flat->gcode.temperature, 230);
}

TEST(OrcaProfile, ABrokenChainNamesTheFileAndTheParent) {
  const fs::path v = orca_vendor();
  test::write_bytes(v / "process" / "orphan.json",
                    R"({"type": "process", "name": "orphan", "inherits": "no_such_parent"})");
  auto r = load_config(v / "process" / "orphan.json");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("orphan.json: inherits 'no_such_parent', which no profile "
                                   "beside it is named"),
            std::string::npos)
      << r.error().message;
  test::write_bytes(v / "process" / "loop_a.json",
                    R"({"type": "process", "name": "loop_a", "inherits": "loop_b"})");
  test::write_bytes(v / "process" / "loop_b.json",
                    R"({"type": "process", "name": "loop_b", "inherits": "loop_a"})");
  auto loop = load_config(v / "process" / "loop_a.json");
  ASSERT_FALSE(loop);
  EXPECT_NE(loop.error().message.find("inherits too deep"), std::string::npos);
  test::write_bytes(v / "process" / "bad.json",
                    R"({"type": "process", "name": "bad", "wall_loops": {"x": 1}})");
  auto bad = load_config(v / "process" / "bad.json");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("bad.json: wall_loops: not a value OrcaSlicer writes"),
            std::string::npos)
      << bad.error().message;
}

}  // namespace
}  // namespace nonplanar
