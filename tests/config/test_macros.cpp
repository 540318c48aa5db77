// PrusaSlicer's macro language: values, precedence, branches, and the errors that keep a
// block from reaching the printer unexpanded.
#include <gtest/gtest.h>

#include "nonplanar/config.hpp"
#include "nonplanar/macros.hpp"

namespace nonplanar {
namespace {

MacroVariables mk3s() {
  MacroVariables v;
  v.set_from_profile("printer_model", "MK3S");
  v.set_from_profile("nozzle_diameter", "0.4");
  v.set_from_profile("first_layer_temperature", "215");
  v.set_from_profile("temperature", "210,200");
  v.set_from_profile("layer_height", "0.07");
  v.set_from_profile("max_print_height", "210");
  v.set_from_profile("z_offset", "0");
  v.set_from_profile("print_settings_id", "0.30mm DRAFT @MK3");
  v.set_from_profile("filament_settings_id", "\"Prusament PLA\";\"Generic PETG\"");
  v.set_from_profile("printer_notes", "PRINTER_VENDOR_PRUSA3D\\nPRINTER_MODEL_MK3\\n");
  v.set("max_layer_z", MacroValue::real(23.45));
  v.set("initial_tool", MacroValue::integer(1));
  v.set("has_wipe_tower", MacroValue::boolean(false));
  return v;
}

std::string ex(const std::string& t) {
  auto r = expand_macros(t, mk3s(), "start_gcode");
  return r ? *r : "ERROR " + r.error().message;
}

TEST(Macros, ExpandsLegacyAndExpressionForms) {
  EXPECT_EQ(ex("M862.3 P \"[printer_model]\" ; check"), "M862.3 P \"MK3S\" ; check");
  EXPECT_EQ(ex("M862.1 P[nozzle_diameter]"), "M862.1 P0.4");
  EXPECT_EQ(ex("M104 S{first_layer_temperature[0]}"), "M104 S215");
  EXPECT_EQ(ex("M104 S[temperature] S{temperature[1]}"), "M104 S210 S200");
  EXPECT_EQ(ex("[filament_settings_id[initial_tool]]"), "Generic PETG");
  EXPECT_EQ(ex("M117 [ok now] {\"a\" + 1}"), "M117 [ok now] a1");  // not a name: literal
}

TEST(Macros, ArithmeticKeepsPrusaSlicersTypes) {
  // MK3S's end lift: z_offset + min(max_layer_z + 1, max_print_height).
  EXPECT_EQ(ex("G1 Z{z_offset+min(max_layer_z+1, max_print_height)}"), "G1 Z24.45");
  EXPECT_EQ(ex("{min(max_layer_z+300, max_print_height)}"), "210");
  EXPECT_EQ(ex("{7/2} {7.0/2} {7%3} {-2*3+1} {(1+2)*3} {2+3*4}"), "3 3.5 1 -5 9 14");
  EXPECT_EQ(ex("{first_layer_temperature[0] * 0.95}"), "204.25");
  EXPECT_EQ(ex("{int(9.7)} {round(9.5)} {digits(3.14159, 6, 2)} {zdigits(7, 3)}"),
            "9 10   3.14 007");
  EXPECT_EQ(ex("{1/3.0}"), "0.333333");  // C++ stream precision, as PrusaSlicer prints
  EXPECT_EQ(ex("{\"\" + ((layer_height<0.1) ? 3 : 5)}"), "3");
}

TEST(Macros, BranchesChooseOneAndSkipTheRest) {
  EXPECT_EQ(ex("M221 S{if layer_height<0.075}100{else}95{endif}"), "M221 S100");
  EXPECT_EQ(ex("{if nozzle_diameter==0.6}A{elsif nozzle_diameter==0.4}B{else}C{endif}"), "B");
  EXPECT_EQ(ex("{if print_settings_id=~/.*(SPEED @MK3|DRAFT @MK3).*/}fast{endif}"), "fast");
  EXPECT_EQ(ex("{if printer_notes=~/.*PRINTER_MODEL_MINI.*/}mini{else}other{endif}"), "other");
  EXPECT_EQ(ex("{if not has_wipe_tower and max_layer_z < max_print_height}up{endif}"), "up");
  // A branch not taken may name what does not exist (PrusaSlicer's own profiles do).
  EXPECT_EQ(ex("{if has_wipe_tower}{no_such_thing}{else}G1 E-2{endif}"), "G1 E-2");
  EXPECT_EQ(ex("{if 1}{if 0}a{elsif 1}b{endif}c{endif}d"), "bcd");
}

TEST(Macros, WhatCannotBeEvaluatedIsAnErrorNamingTheLine) {
  EXPECT_EQ(ex("G28\nG1 Z{max_layer_zz}"),
            "ERROR start_gcode: line 2: 'max_layer_zz' is not a variable");
  EXPECT_EQ(ex("[printer_mode]"), "ERROR start_gcode: line 1: 'printer_mode' is not a variable");
  EXPECT_EQ(ex("{if 1}a"), "ERROR start_gcode: line 1: {if} without {endif}");
  EXPECT_EQ(ex("{endif}"), "ERROR start_gcode: line 1: {endif} without {if}");
  EXPECT_EQ(ex("{1/0}"), "ERROR start_gcode: line 1: division by zero");
  EXPECT_EQ(ex("{temperature[5]}"),
            "ERROR start_gcode: line 1: temperature[5]: index out of range");
  EXPECT_EQ(ex("G1 Z{1+"), "ERROR start_gcode: line 1: '{' is never closed");
  EXPECT_EQ(ex("{printer_model + 1 > 2}"),
            "ERROR start_gcode: line 1: cannot compare MK3S1 with 2");
  EXPECT_EQ(ex("{sqrt(4)}"), "ERROR start_gcode: line 1: 'sqrt' is not a function");
}

// Hostile profiles (#21): what would overflow the stack or be undefined in C++ is an error.
TEST(Macros, HostileExpressionsAreErrors) {
  EXPECT_EQ(ex("{" + std::string(100, '(') + "1" + std::string(100, ')') + "}"), "1");
  EXPECT_EQ(ex("{" + std::string(100000, '(') + "1}"),
            "ERROR start_gcode: line 1: expression nested too deeply");
  EXPECT_EQ(ex("{" + std::string(100000, '-') + "1}"),
            "ERROR start_gcode: line 1: expression nested too deeply");
  EXPECT_EQ(ex("{9223372036854775807 > 0}"), "true");
  EXPECT_EQ(ex("{4000000000 * 4000000000}"), "ERROR start_gcode: line 1: whole-number overflow");
  EXPECT_EQ(ex("{5000000000000000000 + 5000000000000000000}"),
            "ERROR start_gcode: line 1: whole-number overflow");
  EXPECT_EQ(ex("{int(1e300)}"), "ERROR start_gcode: line 1: int(): 1e+300 is out of range");
  EXPECT_EQ(ex("{round(-1e19)}"), "ERROR start_gcode: line 1: round(): -1e+19 is out of range");
  EXPECT_EQ(ex("{int(-2.5)} {round(2.5)}"), "-2 3");
  // Found by the macros fuzzer: a width of 2e17 was cast to int (undefined) before the check.
  EXPECT_EQ(ex("{digits(1.5, 222222222222222222, 1)}"),
            "ERROR start_gcode: line 1: digits(): digits out of range");
  EXPECT_EQ(ex("{zdigits(1.5, 3, -1e300)}"),
            "ERROR start_gcode: line 1: zdigits(): digits out of range");
  // A line of brackets was searched to its end once per bracket: 200 000 of them took minutes.
  const std::string brackets(200000, '[');
  EXPECT_EQ(ex(brackets), brackets);
  EXPECT_EQ(ex("{printer_notes=~/(.|.)*(X|Y)/}"), "false");  // exponential in std::regex
  EXPECT_EQ(ex("{printer_notes=~/.*MK(3|4/}"),
            "ERROR start_gcode: line 1: /.*MK(3|4/: missing ')'");
}

TEST(Macros, ProfileKeysReachTheBlocks) {
  // A profile's keys are kept as written, so a block can name any of them.
  auto c = parse_ini_config(
      "printer_model = MK3S\nbrim_width = 5\nstart_gcode = M862.3 P "
      "\\\"[printer_model]\\\"\\nG28\n");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->profile.at("printer_model"), "MK3S");
  EXPECT_EQ(c->profile.at("brim_width"), "5");
  EXPECT_EQ(c->gcode.start_gcode, "M862.3 P \"[printer_model]\"\nG28");
  MacroVariables v;
  for (const auto& [k, raw] : c->profile) v.set_from_profile(k, raw);
  auto r = expand_macros(c->gcode.start_gcode, v, "start_gcode");
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, "M862.3 P \"MK3S\"\nG28");
  auto f = parse_ini_config(
      "start_filament_gcode = \"M900 K{if nozzle_diameter == 0.6}0.12{else}0.05{endif}\"\n");
  ASSERT_TRUE(f);
  EXPECT_EQ(f->gcode.start_filament_gcode,
            "M900 K{if nozzle_diameter == 0.6}0.12{else}0.05{endif}");
}

}  // namespace
}  // namespace nonplanar
