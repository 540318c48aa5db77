// LineSplicer: a file's kept lines written as a program of their own; every kept extrusion
// lays what it laid in the file, where it laid it, retracted and cooled as it was.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "nonplanar/program.hpp"
#include "program/splice_lines.hpp"

namespace nonplanar::program {
namespace {

// Two objects printed in turn, layer by layer, as PrusaSlicer 2.5 writes a plate: each block
// opens with the retraction after the other's last extrusion, travels, gives it back and
// extrudes a square; b changes the fan; `wipes` puts a wipe after each layer's
// last extrusion, in the next layer (as the MK3S profile's layer change does).
std::string plate_gcode(bool relative, bool wipes) {
  std::string g = relative ? "M83\n" : "M82\n";
  g += "G92 E0\nG1 Z0.3 F7800\nG1 X5 Y-3 F7800\nG1 X60 Y-3 E9 F1000\n";  // a purge line
  double e = relative ? 0 : 9;
  char buf[160];
  auto extrude = [&](double x, double y, double de) {
    e = relative ? de : e + de;
    std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f E%.5f\n", x, y, e);
    g += buf;
  };
  auto pure_e = [&](double de, int f) {
    e = relative ? de : e + de;
    std::snprintf(buf, sizeof buf, "G1 E%.5f F%d\n", e, f);
    g += buf;
  };
  double last_x = 60, last_y = -3;
  for (int layer = 0; layer < 4; ++layer) {
    const double z = 0.2 * (layer + 1);
    std::snprintf(buf, sizeof buf, "%s;LAYER_CHANGE\n;Z:%.1f\n;HEIGHT:0.2\n",
                  layer == 0 ? "M106 S20\n" : "", z);
    g += buf;
    if (wipes && layer > 0) {
      g += ";WIPE_START\nG1 F8640\n";
      e = relative ? -0.3 : e - 0.3;
      std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f E%.5f\n;WIPE_END\n", last_x - 2, last_y, e);
      g += buf;
    }
    std::snprintf(buf, sizeof buf, "G1 Z%.1f F7800\n", z);
    g += buf;
    for (int o = 0; o < 2; ++o) {
      const double x0 = 20 + 40 * o, y0 = 20;
      std::snprintf(buf, sizeof buf, "; printing object %s id:%d copy 0\n", o ? "b" : "a", o);
      g += buf;
      pure_e(wipes && layer > 0 && o == 0 ? -0.5 : -0.8, 2400);
      if (!relative) g += "G92 E0\n", e = 0;
      std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f F7800\n", x0, y0);
      g += buf;
      pure_e(0.8, 2400);
      g += ";TYPE:Perimeter\nG1 F1800\n";
      if (o == 1) {  // b turns the fan up as it goes (a cooling slowdown)
        std::snprintf(buf, sizeof buf, "M106 S%d\n", 60 * layer + 80);
        g += buf;
      }
      extrude(x0 + 10, y0, 0.4 + 0.01 * layer);
      extrude(x0 + 10, y0 + 10, 0.4 + 0.1 * o);
      extrude(x0, y0 + 10, 0.4);
      extrude(x0, y0, 0.4);
      last_x = x0, last_y = y0;
      std::snprintf(buf, sizeof buf, "; stop printing object %s id:%d copy 0\n", o ? "b" : "a", o);
      g += buf;
    }
  }
  g += ";TYPE:Custom\nM107\nG1 Z20 F600\nM84\n";
  return g;
}

// What the printer does at each extrusion: from, to, filament, feed; how much is pulled back
// and the fan then.
struct Laid {
  Vec3 from, to;
  double de, feed, retracted;
  std::string fan;
};
std::vector<Laid> extrusions(const GcodeProgram& p, const std::vector<char>* keep = nullptr) {
  std::vector<Laid> out;
  double retracted = 0;
  std::string fan;
  for (std::size_t i = 0; i < p.lines.size(); ++i) {
    const GcodeLine& l = p.lines[i];
    if (l.kind == GcodeLine::Kind::text &&
        (l.raw.rfind("M106", 0) == 0 || l.raw.rfind("M107", 0) == 0))
      fan = std::string(l.raw);
    if (l.kind != GcodeLine::Kind::move) continue;
    const GcodeMove& m = p.moves[static_cast<std::size_t>(l.move)];
    if (m.has_e && !m.extruding()) retracted -= m.de;
    if (m.extruding() && (!keep || (*keep)[i]))
      out.push_back({m.from, m.to, m.de, m.feed, retracted, fan});
  }
  return out;
}

// Keep object a's lines and the layer changes, drop b's.
std::vector<char> without_b(const GcodeProgram& p) {
  std::vector<char> keep(p.lines.size(), 1);
  bool in_b = false;
  for (std::size_t i = 0; i < p.lines.size(); ++i) {
    const std::string_view raw = p.lines[i].raw;
    if (raw.rfind("; printing object b", 0) == 0) in_b = true;
    if (in_b) keep[i] = 0;
    if (raw.rfind("; stop printing object b", 0) == 0) in_b = false;
  }
  return keep;
}

void expect_same_extrusions(bool relative, bool wipes) {
  SCOPED_TRACE(std::string(relative ? "relative" : "absolute") + (wipes ? ", wipes" : ""));
  const std::string text = plate_gcode(relative, wipes);
  const GcodeProgram file = read_gcode_program(text);
  ASSERT_TRUE(file.problems.empty()) << file.problems[0].why;
  const std::vector<char> keep = without_b(file);
  std::string out;
  std::vector<char> marks;
  LineSplicer s(file);
  s.append(0, file.lines.size(), keep, out, &marks);
  EXPECT_TRUE(s.problem().empty());
  const GcodeProgram spliced = read_gcode_program(out);
  ASSERT_TRUE(spliced.problems.empty()) << spliced.problems[0].why;
  // One mark per line written: the kept lines' 1, the added lines' 0.
  EXPECT_EQ(marks.size(), spliced.lines.size());
  std::size_t kept = 0;
  for (const char k : keep) kept += k != 0;
  // Less the wipes retracting in place (one in each layer after the first).
  EXPECT_EQ(static_cast<std::size_t>(std::count(marks.begin(), marks.end(), 1)),
            kept - (wipes ? 3 : 0));
  if (!relative) {
    EXPECT_GT(marks.size(), kept);  // E to restore after each of b's blocks
  }
  const auto want = extrusions(file, &keep), got = extrusions(spliced);
  ASSERT_EQ(got.size(), want.size());
  ASSERT_EQ(got.size(), 17u);  // the purge line, a's 4 squares
  for (std::size_t k = 0; k < got.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_LT((got[k].from - want[k].from).norm(), 1e-9);
    EXPECT_LT((got[k].to - want[k].to).norm(), 1e-9);
    EXPECT_NEAR(got[k].de, want[k].de, 1e-9);
    EXPECT_NEAR(got[k].feed, want[k].feed, 1e-9);
    EXPECT_NEAR(got[k].retracted, want[k].retracted, 1e-6);
    EXPECT_EQ(got[k].fan, want[k].fan);
  }
}

TEST(LineSplicer, KeptExtrusionsLayWhatTheyLaidInTheFile) {
  expect_same_extrusions(false, false);
  expect_same_extrusions(true, false);
  expect_same_extrusions(false, true);
  expect_same_extrusions(true, true);
}

// A wipe after a dropped block would retrace b's square from wherever a's head was: it pulls
// its filament back in place instead.
TEST(LineSplicer, AWipeOfADroppedExtrusionRetractsInPlace) {
  const std::string text = plate_gcode(true, true);
  const GcodeProgram file = read_gcode_program(text);
  std::string out;
  LineSplicer s(file);
  s.append(0, file.lines.size(), without_b(file), out);
  const GcodeProgram spliced = read_gcode_program(out);
  int wipes = 0;
  for (const GcodeMove& m : spliced.moves)
    if (m.wipe && m.has_e) {
      ++wipes;
      EXPECT_FALSE(m.has_xy) << "line " << m.line;
      EXPECT_NEAR(m.de, -0.3, 1e-9);
    }
  EXPECT_EQ(wipes, 3);
}

// Where the file's head was before a kept extrusion that follows no travel of its own.
TEST(LineSplicer, AnExtrusionAfterADroppedTravelStartsWhereTheFilesDid) {
  const std::string text =
      "M83\nG1 X0 Y0 Z0.2 F7800\n;LAYER_CHANGE\n;Z:0.2\nG1 X10 Y10 F7800\nG1 F1500\n"
      "G1 X20 Y10 E1\nG91\n";
  const GcodeProgram file = read_gcode_program(text);
  std::vector<char> keep(file.lines.size(), 1);
  keep[4] = 0;  // the travel
  std::string out;
  LineSplicer s(file);
  s.append(0, file.lines.size() - 1, keep, out);
  EXPECT_TRUE(s.problem().empty());
  const auto got = extrusions(read_gcode_program(out));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_LT((got[0].from - Vec3(10, 10, 0.2)).norm(), 1e-9) << out;
  EXPECT_NEAR(got[0].feed, 1500, 1e-9);
  s.append(file.lines.size() - 1, file.lines.size(), keep, out);
  EXPECT_NE(s.problem().find("G91"), std::string::npos);
  // A start G-code's own G91 (a lift before homing) is its business.
  const std::string lifted = "G91\nG1 Z5\nG90\n" + text.substr(0, text.find("G91"));
  const GcodeProgram start = read_gcode_program(lifted);  // (it views the text)
  std::string out2;
  LineSplicer s2(start);
  s2.append(0, start.lines.size(), std::vector<char>(start.lines.size(), 1), out2);
  EXPECT_TRUE(s2.problem().empty()) << s2.problem();
}

// A dropped travel with its retraction and feed rate (a support's, whose ;TYPE: it carries):
// the splice travels retracted, gives the filament back, and restores the extrusion's feed.
TEST(LineSplicer, ATravelItAddsIsRetractedAround) {
  for (const bool relative : {false, true}) {
    SCOPED_TRACE(relative ? "relative" : "absolute");
    const std::string text = std::string(relative ? "M83\n" : "M82\n") +
                             "G92 E0\nG1 X0 Y0 Z0.2 F7800\n;LAYER_CHANGE\n;Z:0.2\n"
                             "G1 F1500\nG1 X10 Y0 E" +
                             (relative ? "0.5" : "0.5") + "\nG1 E" + (relative ? "-0.8" : "-0.3") +
                             " F2100\nG1 X30 Y20 F9000\nG1 E" + (relative ? "0.8" : "0.5") +
                             " F1800\nG1 F1200\nG1 X40 Y20 E" + (relative ? "0.5" : "1.0") + "\n";
    const GcodeProgram file = read_gcode_program(text);
    ASSERT_TRUE(file.problems.empty());
    EXPECT_NEAR(file.retraction.length, 0.8, 1e-9);
    std::vector<char> keep(file.lines.size(), 1);
    for (std::size_t i = 7; i <= 10; ++i) keep[i] = 0;  // retract, travel, give back, F
    std::string out;
    LineSplicer s(file);
    s.append(0, file.lines.size(), keep, out);
    const GcodeProgram spliced = read_gcode_program(out);
    const auto want = extrusions(file), got = extrusions(spliced);
    ASSERT_EQ(got.size(), 2u) << out;
    EXPECT_LT((got[1].from - want[1].from).norm(), 1e-9) << out;
    EXPECT_NEAR(got[1].de, want[1].de, 1e-9) << out;
    EXPECT_NEAR(got[1].feed, 1200, 1e-9) << out;
    EXPECT_NEAR(got[1].retracted, 0, 1e-9) << out;
    double retracted = 0;
    int travels = 0;
    for (const GcodeMove& m : spliced.moves) {
      if (m.has_e && !m.extruding()) retracted -= m.de;
      if (m.has_xy && !m.has_e && (m.to - m.from).head<2>().norm() > 2) {
        ++travels;
        EXPECT_NEAR(retracted, 0.8, 1e-9) << out;  // the travel goes pulled back
      }
    }
    EXPECT_EQ(travels, 1) << out;
  }
}

}  // namespace
}  // namespace nonplanar::program
