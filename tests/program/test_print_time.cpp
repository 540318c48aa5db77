// The time estimate (program/print_time.cpp) on moves whose trapezoids can be worked out by
// hand, and the stats pass (gcode/print_stats.cpp) that writes it into a file.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "nonplanar/gcode.hpp"
#include "nonplanar/print_time.hpp"

namespace nonplanar {
namespace {

double seconds(const std::string& gcode, const MachineLimits& m) {
  return estimate_print_time(read_gcode_program(gcode), m).total;
}

MachineLimits no_jerk() {
  MachineLimits m;
  m.jerk_x = m.jerk_y = m.jerk_z = m.jerk_e = 0;  // every block starts and ends at rest
  return m;
}

TEST(PrintTime, OneMoveIsATrapezoidOrATriangle) {
  MachineLimits m = no_jerk();
  m.accel_travel = 1000;
  // 100 mm at 50 mm/s, 1000 mm/s²: 1.25 mm up, 97.5 mm flat, 1.25 mm down.
  EXPECT_NEAR(seconds("G1 X100 F3000\n", m), 2 * 0.05 + 97.5 / 50, 1e-9);
  // 1 mm cannot reach 100 mm/s: the ramps meet at sqrt(a d), t = 2 sqrt(d / a).
  EXPECT_NEAR(seconds("G1 X1 F6000\n", m), 2 * std::sqrt(1.0 / 1000), 1e-9);
  // Jerk as large as the speed: no ramps at all.
  m.jerk_x = m.jerk_y = 100;
  EXPECT_NEAR(seconds("G1 X100 F3000\n", m), 2.0, 1e-9);
}

TEST(PrintTime, LimitsFromTheProfileAndTheFile) {
  MachineLimits m = no_jerk();
  m.accel_travel = m.accel_extruding = 1000;
  // M203 caps X at 10 mm/s: 100 mm takes 10 s plus the ramps (2 × 0.01 s − 0.1 mm / 10).
  EXPECT_NEAR(seconds("M203 X10\nG1 X100 F3000\n", m), 10 + 0.01, 1e-9);
  // M204 S500 halves the acceleration: ramps of 0.1 s, 2.5 mm each.
  EXPECT_NEAR(seconds("M204 S500\nG1 X100 F3000\n", m), 0.2 + 95.0 / 50, 1e-9);
  // A diagonal's acceleration is capped by the axis it loads: M201 X100 on a 45° move.
  const double a = 100 * std::sqrt(2.0), d = 100 * std::sqrt(2.0), v = 50;
  EXPECT_NEAR(seconds("M201 X100\nG1 X100 Y100 F3000\n", m), 2 * v / a + (d - v * v / a) / v, 1e-9);
  // A dwell and a retraction (E only, at the retract acceleration).
  m.accel_retracting = 1000;
  EXPECT_NEAR(seconds("G4 P500\nG1 E-1 F2400\n", m), 0.5 + 2 * std::sqrt(1.0 / 1000), 1e-9);
}

TEST(PrintTime, JunctionsKeepSpeedWhereJerkAllows) {
  // Two collinear 50 mm moves at the same speed: the junction is not a stop, so the pair
  // takes exactly what one 100 mm move takes; a 90° corner with no jerk stops in between.
  MachineLimits m = no_jerk();
  m.accel_travel = 1000;
  const double straight = seconds("G1 X50 F3000\nG1 X100\n", m);
  EXPECT_NEAR(straight, seconds("G1 X100 F3000\n", m), 1e-9);
  const double corner = seconds("G1 X50 F3000\nG1 X50 Y50\n", m);
  EXPECT_NEAR(corner, 2 * seconds("G1 X50 F3000\n", m), 1e-9);
  EXPECT_EQ(format_duration(3723.4), "1h 2m 3s");
  EXPECT_EQ(format_duration(1382), "23m 2s");
  EXPECT_EQ(format_duration(45), "45s");
}

// Marlin 2's junction deviation δ (#16): a corner of angle θ between two directions is
// driven at v² = a δ sin(θ/2) / (1 − sin(θ/2)) instead of the jerk limits.
TEST(PrintTime, JunctionDeviationSetsTheCornerSpeed) {
  MachineLimits m = no_jerk();
  m.accel_travel = 1000;
  m.junction_deviation = 0.05;
  // Two 50 mm moves at 50 mm/s, square to each other: accelerate from rest, cruise, slow to
  // the corner's speed, and the mirror image after it.
  const double a = 1000, v = 50, s = std::sqrt(0.5);
  const double vj = std::sqrt(a * 0.05 * s / (1 - s));  // 10.99 mm/s
  const double one =
      v / a + (v - vj) / a + (50 - v * v / (2 * a) - (v * v - vj * vj) / (2 * a)) / v;
  const std::string corner = "G1 X50 F3000\nG1 X50 Y50\n";
  EXPECT_NEAR(seconds(corner, m), 2 * one, 1e-9);
  // The same δ from the file's M205 J, the profile's being 0.
  MachineLimits from_file = m;
  from_file.junction_deviation = 0;
  EXPECT_NEAR(seconds("M205 J0.05\n" + corner, from_file), 2 * one, 1e-9);
  // Jerk no longer matters once δ is set; a straight joint keeps full speed; a reversal stops.
  MachineLimits jerky = m;
  jerky.jerk_x = jerky.jerk_y = 100;
  EXPECT_NEAR(seconds(corner, jerky), 2 * one, 1e-9);
  EXPECT_NEAR(seconds("G1 X50 F3000\nG1 X100\n", m), seconds("G1 X100 F3000\n", m), 1e-9);
  EXPECT_NEAR(seconds("G1 X50 F3000\nG1 X0\n", m), 2 * seconds("G1 X50 F3000\n", m), 1e-9);
  // A larger δ takes the corner faster.
  MachineLimits loose = m;
  loose.junction_deviation = 0.2;
  EXPECT_LT(seconds(corner, loose), seconds(corner, m) - 0.01);
}

TEST(PrintTime, ShortMovesAtAGentleTurnAreDrivenAsAnArc) {
  // Two 0.5 mm moves turning 44°, a δ so large it limits nothing: the firmware drives such a
  // turn as an arc through the move's length, v² ≤ d a / θ (θ by its acos, within 0.033 rad).
  // Each move is then a triangle from rest up and down to that speed (and back).
  MachineLimits m = no_jerk();
  m.accel_travel = 1000;
  m.junction_deviation = 50;
  const double a = 1000, d = 0.5, turn = 44 * M_PI / 180;
  char buf[128];
  std::snprintf(buf, sizeof buf, "G1 X0.5 F3000\nG1 X%.9f Y%.9f\n", d + d * std::cos(turn),
                d * std::sin(turn));
  auto pair_time = [&](double vj2) {  // rest → peak → √vj2, twice
    const double up = (2 * a * d + vj2) / (4 * a), peak = std::sqrt(2 * a * up);
    return 2 * (peak / a + (peak - std::sqrt(vj2)) / a);
  };
  const double t = seconds(buf, m);
  EXPECT_GT(t, pair_time(d * a / (turn - 0.033)) - 1e-9);  // a smaller θ: a faster turn
  EXPECT_LT(t, pair_time(d * a / (turn + 0.033)) + 1e-9);
  // Without the arc the junction would be as fast as the moves allow (v² = 2 a d).
  EXPECT_GT(t, pair_time(2 * a * d) + 4e-4);
}

TEST(PrintStats, FooterAndProgressAreRecomputedInPlace) {
  PrintConfig c;
  c.profile["remaining_times"] = "1";
  c.profile["filament_density"] = "1.24";
  c.profile["machine_max_acceleration_extruding"] = "1000";
  c.profile["machine_max_jerk_x"] = "0";
  c.profile["machine_max_jerk_y"] = "0";
  c.profile["machine_max_jerk_e"] = "0";
  // An engine's file: stale M73 and footer for the flattened part, then its config block.
  const std::string in =
      "M73 P0 R99\nG90\nM83\n;LAYER_CHANGE\n;Z:0.2\nG1 X100 E10 F3000\n;LAYER_CHANGE\n;Z:0.4\n"
      "M73 P50 R50\nG1 X0 E10\n;TYPE:Custom\nM84\n; filament used [mm] = 999.00\n"
      "; estimated printing time (normal mode) = 9h 0m 0s\n"
      "; prusaslicer_config = begin\n; layer_height = 0.2\n; prusaslicer_config = end\n";
  PrintStats s;
  const std::string out = with_print_stats(in, c, &s);
  EXPECT_NEAR(s.seconds, 2 * (2 * 0.05 + 97.5 / 50), 1e-9);  // two 100 mm extrusions
  EXPECT_NEAR(s.filament_mm, 20, 1e-12);
  EXPECT_NEAR(s.filament_g, 20 * M_PI * 0.25 * 1.75 * 1.75 / 1000 * 1.24, 1e-12);
  const std::string want =
      "M73 P0 R0\nG90\nM83\nM73 P0 R0\n;LAYER_CHANGE\n;Z:0.2\nG1 X100 E10 F3000\n"
      "M73 P50 R0\n;LAYER_CHANGE\n;Z:0.4\nG1 X0 E10\nM73 P100 R0\n;TYPE:Custom\nM84\n"
      "; filament used [mm] = 20.00\n; filament used [cm3] = 0.05\n; filament used [g] = 0.06\n"
      "; estimated printing time (normal mode) = 4s\n"
      "; prusaslicer_config = begin\n; layer_height = 0.2\n; prusaslicer_config = end\n";
  EXPECT_EQ(out, want);
  // The same in place (the gate's way: measured, then stamped into the text itself), from
  // CRLF lines and no line end after the last.
  std::string crlf;
  for (char ch : in) ch == '\n' ? void(crlf += "\r\n") : void(crlf += ch);
  crlf.resize(crlf.size() - 2);
  std::string stamped = crlf;
  stamp_print_stats(stamped, measure_print_stats(crlf, c));
  EXPECT_EQ(stamped, want);
  // Without remaining_times: no M73 at all, the footer still recomputed.
  c.profile.erase("remaining_times");
  const std::string plain = with_print_stats(in, c);
  EXPECT_EQ(plain.find("M73"), std::string::npos);
  EXPECT_NE(plain.find("; estimated printing time (normal mode) = 4s\n"), std::string::npos);
}

// The MK3S's stealth mode: PrusaSlicer estimates it too (silent_mode = 1, Marlin, a second
// value in the machine limits), and writes "M73 Q S" beside every "M73 P R".
TEST(PrintStats, SilentModeHasItsOwnEstimateAndProgress) {
  PrintConfig c;
  c.profile["remaining_times"] = "1";
  c.profile["silent_mode"] = "1";
  c.profile["machine_max_acceleration_x"] = "1000,960";
  c.profile["machine_max_acceleration_extruding"] = "1000,250";
  c.profile["machine_max_feedrate_x"] = "200,20";  // the silent mode caps X at 20 mm/s
  for (const char* k : {"machine_max_jerk_x", "machine_max_jerk_y", "machine_max_jerk_e"})
    c.profile[k] = "0";
  ASSERT_TRUE(silent_mode_estimate(c));
  const std::string in = "G90\nM83\n;LAYER_CHANGE\n;Z:0.2\nG1 X100 E10 F3000\n;TYPE:Custom\nM84\n";
  // Normal: 1000 mm/s² to 50 mm/s, 2.05 s. Silent: 250 mm/s² to 20 mm/s (0.8 mm each way),
  // 98.4 / 20 + 2 × 0.08 = 5.08 s.
  EXPECT_NEAR(estimate_print_time(read_gcode_program(in), machine_limits(c)).total, 2.05, 1e-9);
  EXPECT_NEAR(estimate_print_time(read_gcode_program(in), machine_limits(c, 1)).total, 5.08, 1e-9);
  const std::string out = with_print_stats(in, c);
  EXPECT_NE(out.find("M73 P0 R0\nM73 Q0 S0\nG90"), std::string::npos) << out;
  EXPECT_NE(out.find("M73 P100 R0\nM73 Q100 S0\n;TYPE:Custom"), std::string::npos) << out;
  EXPECT_NE(out.find("; estimated printing time (normal mode) = 2s\n"
                     "; estimated printing time (silent mode) = 5s\n"),
            std::string::npos)
      << out;
  // Not on Klipper, nor without the second values, nor with silent_mode = 0.
  for (auto change : {std::pair<std::string, std::string>{"gcode_flavor", "klipper"},
                      {"machine_max_acceleration_x", "1000"},
                      {"silent_mode", "0"}}) {
    PrintConfig d = c;
    if (change.first == "gcode_flavor")
      d.gcode.flavor = GcodeFlavor::klipper;
    else
      d.profile[change.first] = change.second;
    EXPECT_FALSE(silent_mode_estimate(d)) << change.first;
    EXPECT_EQ(with_print_stats(in, d).find("M73 Q"), std::string::npos) << change.first;
  }
}

// with_print_stats reads a file line by line (for_each_gcode_line into a PrintTimer) instead
// of holding it read: every line's start time must be the whole program's, to the bit.
// #20: past 256 queued blocks all but the last 64 are timed for good, as PrusaSlicer's
// estimate does. 64 blocks of 0.1 mm are room enough to slow down in, so 1000 collinear
// moves still take what one move of their length takes.
TEST(PrintTime, AQueueOf64BlocksKeepsALongRunAtFullSpeed) {
  MachineLimits m;  // jerk 10 mm/s: the first move starts at 10, the last ends at 10
  m.accel_travel = 1000;
  std::string many = "G1 X0.1 F3000\n";
  for (int k = 2; k <= 1000; ++k) many += "G1 X" + std::to_string(k * 0.1) + "\n";
  EXPECT_NEAR(seconds(many, m), seconds("G1 X100 F3000\n", m), 1e-9);
}

TEST(PrintTime, StreamedLineByLineIsTheWholeProgramsEstimate) {
  std::string in = "M201 X900 Y900\nM204 S800 T1200\nG90\nM83\nG92 E0\n";
  for (int k = 0; k < 200; ++k) {
    in += ";LAYER_CHANGE\n;Z:" + std::to_string(0.2 * (k + 1)) + "\n";
    in += "G1 Z" + std::to_string(0.2 * (k + 1)) + " F600\n";
    in += "G1 X" + std::to_string(10 + k % 7) + " Y" + std::to_string(20 + k % 5) + " E0.4 F1800\n";
    in += "G1 X30 Y" + std::to_string(5 + k % 3) + " E0.9\nG1 E-0.8 F2100\n";
    if (k % 50 == 0) in += "G4 P250\nM205 X8 Y8\n";
  }
  const GcodeProgram whole = read_gcode_program(in);
  const PrintTime want = estimate_print_time(whole, MachineLimits{});
  PrintTimer timer(MachineLimits{});
  const GcodeProgram skeleton =
      for_each_gcode_line(in, [&](const GcodeLine& l, const GcodeMove* m) {
        EXPECT_EQ(m != nullptr, l.kind == GcodeLine::Kind::move);
        timer.line(l, m);
      });
  const PrintTime got = timer.finish();
  EXPECT_GT(want.total, 10);
  EXPECT_EQ(got.total, want.total);
  ASSERT_EQ(got.line_start.size(), whole.lines.size() + 1);
  EXPECT_EQ(got.line_start, want.line_start);
  // The skeleton keeps the per-file figures, not the lines.
  EXPECT_EQ(skeleton.print_begin, whole.print_begin);
  EXPECT_EQ(skeleton.print_end, whole.print_end);
  EXPECT_TRUE(skeleton.lines.empty());
  EXPECT_TRUE(skeleton.moves.empty());
}

}  // namespace
}  // namespace nonplanar
