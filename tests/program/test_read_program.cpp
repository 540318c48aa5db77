// The one G-code reader and the one emitter (src/program/): what each line is, what each
// move carries, what is a problem and where; the emitter's formats and E bookkeeping.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "nonplanar/deform.hpp"
#include "nonplanar/program.hpp"
#include "program/gcode_text.hpp"

namespace nonplanar {
namespace {

using Kind = GcodeLine::Kind;

// The start of a stock Original Prusa MK3S file (PrusaSlicer 2.5), a Klipper print's object
// labels, and an end G-code after ;TYPE:Custom.
const std::string kPrusaStart =
    "M73 P0 R12\n"
    "M862.3 P \"MK3S\" ; printer model check\n"
    "M862.1 P0.4 ; nozzle diameter check\n"
    "M115 U3.13.2 ; tell printer latest fw version\n"
    "G90 ; use absolute coordinates\n"
    "M83 ; extruder relative mode\n"
    "G28 W ; home all without mesh bed level\n"
    "G80 ; mesh bed leveling\n"
    "G1 Y-3.0 F1000.0 ; go outside print area\n"
    "G1 X60.0 E9.0 F1000.0 ; intro line\n"
    "M221 S95\n"
    "M900 K0.04 ; Filament gcode LA 1.5\n"
    "M107\n";
const std::string kPrint =
    ";LAYER_CHANGE\n"
    ";Z:0.2\n"
    ";HEIGHT:0.2\n"
    "EXCLUDE_OBJECT_START NAME=cube_id_0_copy_0\n"
    "SET_PRINT_STATS_INFO CURRENT_LAYER=1\n"
    "G1 E-0.8 F2100\n"
    "G1 Z0.2 F720\n"
    "G1 X10 Y10 F7200\n"
    "G1 E0.8 F2100\n"
    ";TYPE:External perimeter\n"
    ";WIDTH:0.42\n"
    "G1 F1200\n"
    "G1 X20 Y10 E0.5\n"
    "G1 X20 Y20 E0.5\n"
    "M73 P50 R6\n"
    "EXCLUDE_OBJECT_END NAME=cube_id_0_copy_0\n"
    ";LAYER_CHANGE\n"
    ";Z:0.4\n"
    ";HEIGHT:0.2\n"
    "G1 Z0.4 F720\n"
    ";TYPE:Top solid infill\n"
    "G1 X10 Y20 E0.5\n"
    "print_layer_done\n";
const std::string kEnd =
    ";TYPE:Custom\n"
    "G1 Z30.4 F720 ; Move print head up\n"
    "G1 X0 Y200 F3600 ; park\n"
    "M84 ; disable motors\n";

TEST(ReadProgram, StockPrusaAndKlipperLinesPassAsText) {
  const std::string text = kPrusaStart + kPrint + kEnd;
  const GcodeProgram p = read_gcode_program(text);
  ASSERT_EQ(p.problems.size(), 1u);  // G28 W: home, fine outside the print
  EXPECT_TRUE(p.problems[0].moves_head);
  EXPECT_EQ(p.problems[0].line, 7);
  EXPECT_EQ(p.lines.size(), 40u);
  EXPECT_EQ(p.print_begin, 13u);            // the first ;LAYER_CHANGE
  EXPECT_EQ(p.print_end, 36u);              // the ;TYPE:Custom after the last typed extrusion
  EXPECT_EQ(p.lines[1].kind, Kind::text);   // M862.3
  EXPECT_EQ(p.lines[16].kind, Kind::text);  // EXCLUDE_OBJECT_START
  EXPECT_EQ(p.lines[5].kind, Kind::e_mode);
  EXPECT_EQ(p.lines[14].kind, Kind::z_comment);
  EXPECT_EQ(p.lines[15].kind, Kind::height_comment);
  EXPECT_EQ(p.fan_at_print, "M107");
  EXPECT_TRUE(p.at_print.relative_e);
  ASSERT_EQ(p.layer_z.size(), 2u);
  EXPECT_DOUBLE_EQ(p.layer_z[1], 0.4);
  EXPECT_NEAR(p.retraction.length, 0.8, 1e-12);
  EXPECT_NEAR(p.retraction.f, 2100, 1e-12);
  // Moves: every G0/G1, with the type, width and layer in force, and the feed rate.
  ASSERT_EQ(p.moves.size(), 13u);
  const GcodeMove& m = p.moves[7];  // G1 X20 Y10 E0.5
  EXPECT_EQ(m.line, 26);
  EXPECT_TRUE(m.extruding());
  EXPECT_NEAR(m.de, 0.5, 1e-12);
  EXPECT_EQ(m.type, "External perimeter");
  EXPECT_NEAR(m.width, 0.42, 1e-12);
  EXPECT_EQ(m.layer, 0);
  EXPECT_NEAR(m.feed, 1200, 1e-12);
  EXPECT_TRUE(std::isnan(m.f));
  EXPECT_EQ(p.moves[10].layer, 1);
  EXPECT_EQ(p.moves[10].type, "Top solid infill");
  // check reads it (home is no reason to refuse a file), and so does the mapping.
  auto moves = read_gcode_moves(text);
  ASSERT_TRUE(moves) << moves.error().message;
  EXPECT_EQ(moves->size(), 13u);
  const auto field = planar_field({});
  auto mapped = map_foreign_gcode(text, *field, {}, {});
  ASSERT_TRUE(mapped) << mapped.error().message;
  EXPECT_NE(mapped->text().find("EXCLUDE_OBJECT_START NAME=cube_id_0_copy_0\n"), std::string::npos);
  EXPECT_NE(mapped->text().find("M862.3 P \"MK3S\""), std::string::npos);
  EXPECT_NE(mapped->text().find("\nprint_layer_done\n"), std::string::npos);
}

TEST(ReadProgram, ProblemsNameTheirLines) {
  const GcodeProgram p = read_gcode_program(
      "G1 X1 Y1\nhello world\nG2 X5 Y5 I1 J1\nG1 X2 Q4\nG20\nG5\nG1X10Y10\nG1 Xnan\nG29\n");
  ASSERT_EQ(p.problems.size(), 8u);
  for (std::size_t k = 0; k < p.problems.size(); ++k)
    EXPECT_EQ(p.problems[k].line, static_cast<int>(k) + 2) << p.problems[k].why;
  EXPECT_NE(p.problems[1].why.find("arc"), std::string::npos);
  EXPECT_NE(p.problems[2].why.find("'Q4'"), std::string::npos);
  EXPECT_TRUE(p.problems[7].moves_head);
  EXPECT_FALSE(p.problems[0].moves_head);
  // The move with a bad word is still read, without the word.
  EXPECT_EQ(p.moves.size(), 3u);
  EXPECT_NEAR(p.moves[1].to.x(), 2, 1e-12);
  // Inside the print, the mapping refuses home and probe and macros pass.
  const auto field = planar_field({});
  const std::string head = ";LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 X1 Y1 E1\n";
  EXPECT_TRUE(map_foreign_gcode(head + "BED_MESH_CALIBRATE\n", *field, {}, {}));
  auto home = map_foreign_gcode(head + "G28\n", *field, {}, {});
  ASSERT_FALSE(home);
  EXPECT_NE(home.error().message.find("line 5: 'G28' (home or probe)"), std::string::npos)
      << home.error().message;
}

TEST(ReadProgram, RelativeAxesAndResets) {
  const GcodeProgram p =
      read_gcode_program("G92 E5\nG1 X1 Y0 E6\nG91\nG1 X1 E0.5\nG90\nM83\nG1 X0 E0.25\n");
  ASSERT_EQ(p.moves.size(), 3u);
  EXPECT_NEAR(p.moves[0].de, 1, 1e-12);  // absolute: 6 − 5
  EXPECT_NEAR(p.moves[1].to.x(), 2, 1e-12);
  EXPECT_NEAR(p.moves[1].de, 0.5, 1e-12);  // G91 makes E relative too
  EXPECT_NEAR(p.moves[2].de, 0.25, 1e-12);
  EXPECT_EQ(p.lines[0].kind, Kind::e_reset);
  EXPECT_EQ(p.lines[2].kind, Kind::xyz_relative);
  EXPECT_NEAR(p.at_end.e, 6.75, 1e-12);
  EXPECT_TRUE(p.at_end.relative_e);
}

// PrusaSlicer puts supports on layers of their own between the part's: the part's layer after
// one has the distance from it in its header, and its beads their own ;HEIGHT:. A bridge's
// ;HEIGHT: is its round bead's (the nozzle), not a thickness.
TEST(ReadProgram, EachBeadKeepsItsOwnThickness) {
  const std::string g =
      "G1 Z0.4\n;LAYER_CHANGE\n;Z:0.496\n;HEIGHT:0.096\n;TYPE:Support material\n;HEIGHT:0.296\n"
      "G1 X1 Y1 E1\n;LAYER_CHANGE\n;Z:0.6\n;HEIGHT:0.104\n;TYPE:Perimeter\n;HEIGHT:0.2\n"
      "G1 Z0.6\nG1 X2 Y1 E2\n;TYPE:Bridge infill\n;HEIGHT:0.4\nG1 X3 Y1 E3\n";
  const GcodeProgram p = read_gcode_program(g);
  ASSERT_TRUE(p.problems.empty());
  ASSERT_EQ(p.layer_height.size(), 2u);
  EXPECT_DOUBLE_EQ(p.layer_height[0], 0.096);  // the headers'
  EXPECT_DOUBLE_EQ(p.layer_height[1], 0.104);
  std::vector<double> h;
  for (const GcodeMove& m : p.moves)
    if (m.extruding()) h.push_back(m.height);
  EXPECT_EQ(h, (std::vector<double>{0.296, 0.2, 0.2}));
}

// A layer of the part after one of supports alone whose first path is an overhang: the
// header's ;HEIGHT: is the distance from the support's layer (0.06), and the overhang's own
// is its bead's; its thickness is the part's, from its last layer (0.18), as the perimeter
// after it says. Read 0.06 thick, it stopped a shell with supports on at the safety check.
TEST(ReadProgram, AnOverhangAfterASupportLayerIsAsThickAsThePartsLayer) {
  const std::string g =
      "G1 Z2.04\n;LAYER_CHANGE\n;Z:2.04\n;HEIGHT:0.06\n;TYPE:Perimeter\n;HEIGHT:0.18\n"
      "G1 X1 Y1 E1\n;LAYER_CHANGE\n;Z:2.16\n;HEIGHT:0.12\n;TYPE:Support material interface\n"
      "G1 Z2.16\nG1 X2 Y1 E2\n;LAYER_CHANGE\n;Z:2.22\n;HEIGHT:0.06\nG1 Z2.22\n"
      ";TYPE:Overhang perimeter\n;HEIGHT:0.4\nG1 X3 Y1 E3\n;TYPE:Perimeter\n;HEIGHT:0.18\n"
      "G1 X4 Y1 E4\n;TYPE:Bridge infill\n;HEIGHT:0.4\nG1 X5 Y1 E5\n"
      ";LAYER_CHANGE\n;Z:2.4\n;HEIGHT:0.18\nG1 Z2.4\n;TYPE:Overhang perimeter\nG1 X6 Y1 E6\n";
  const GcodeProgram p = read_gcode_program(g);
  ASSERT_TRUE(p.problems.empty());
  std::vector<double> h;
  for (const GcodeMove& m : p.moves)
    if (m.extruding()) h.push_back(m.height);
  ASSERT_EQ(h.size(), 6u);
  EXPECT_DOUBLE_EQ(h[1], 0.12);   // the support's: its layer's (no ;HEIGHT: of its own)
  EXPECT_NEAR(h[2], 0.18, 1e-9);  // the overhang: over the part's layer at 2.04
  EXPECT_DOUBLE_EQ(h[3], 0.18);
  EXPECT_DOUBLE_EQ(h[4], 0.18);  // a bridge after the perimeter: the thickness in force
  EXPECT_DOUBLE_EQ(h[5], 0.18);  // no support layer between: the header's
  EXPECT_DOUBLE_EQ(p.layer_height[2], 0.06);  // the layers' own heights are the headers'
}

TEST(GcodeText, WritesTheWordsAskedForAndKeepsE) {
  program::GcodeText abs(false, 1.0);
  ProgramMove m;
  m.to = Vec3(1.23456, 2, 0.2), m.xy = true, m.de = 0.5, m.f = 1799.6;
  abs.move(m);
  m.to = Vec3(1, 2, 0.3), m.xy = false, m.z = true, m.de = -0.8, m.f = kNoValue;
  m.comment = "retract";
  abs.move(m);
  EXPECT_EQ(abs.out, "G1 X1.235 Y2.000 E1.50000 F1800\nG1 Z0.300 E0.70000 ; retract\n");
  // A number no printer takes does not fit a line: the program is refused, not truncated.
  program::GcodeText rel(true);
  m.z = false, m.xy = true, m.de = 1e300, m.comment = nullptr;
  rel.move(m);
  ASSERT_TRUE(rel.fault);
}

// A layer as steps (program.hpp), written by the one writer: each step's lines in order, E
// followed across the steps that set it, values filled in after the moves.
TEST(ProgramLayer, StepsAreWrittenInOrderAndFollowE) {
  using StepKind = ProgramStep::Kind;
  ProgramLayer L;
  L.raw(";LAYER_CHANGE");
  const std::size_t z = L.z_comment(0);
  L.e_mode("M83", true);
  L.start(StepKind::extrusion, ExtrusionRole::top_solid_infill, 0.42);
  L.move_from(Vec3(0, 0, 0.2), Vec3(0.0004, 0, 0.2), 0.1, kNoValue);  // under 0.5 µm: no XY
  L.move_from(Vec3(0, 0, 0.2), Vec3(0, 0, 0.2), kNoValue, kNoValue);  // nothing to write
  L.move_from(Vec3(0, 0, 0.2), Vec3(3, 0, 0.25), 0.2, kNoValue, 0.25);
  L.lifted_travel(Vec3(3, 0, 0.25), Vec3(5, 0, 1.2), 1.6, 9000, kNoValue);
  L.e_mode("M82", false);
  L.e_reset("G92 E5", 5);
  L.start(StepKind::retract);
  L.move_from(Vec3(5, 0, 1.2), Vec3(5, 0, 1.2), -0.8, 2100);
  L.block("M104 S200\nM140 S60\n");
  L.steps[z].value = 0.25;
  ASSERT_EQ(L.steps.size(), 9u);
  EXPECT_EQ(L.steps[3].kind, StepKind::extrusion);
  EXPECT_EQ(L.steps[3].end - L.steps[3].begin, 2u);
  EXPECT_EQ(L.steps[3].role, ExtrusionRole::top_solid_infill);
  EXPECT_DOUBLE_EQ(L.moves[1].height, 0.25);
  EXPECT_EQ(L.steps[4].kind, StepKind::travel);
  EXPECT_EQ(L.steps[4].end - L.steps[4].begin, 3u);
  program::GcodeText w(false, 2.0);
  program::write_program_layer(w, L);
  EXPECT_EQ(w.out,
            ";LAYER_CHANGE\n;Z:0.250\nM83\nG1 E0.10000\nG1 X3.000 Y0.000 Z0.250 E0.20000\n"
            "G1 Z1.600 F9000\nG1 X5.000 Y0.000\nG1 Z1.200\nM82\nG92 E5\nG1 E4.20000 F2100\n"
            "M104 S200\nM140 S60\n");
  EXPECT_FALSE(w.fault);
  // A line too long to send refuses the layer when it is written.
  L.clear();
  L.line(";%s", std::string(300, 'x').c_str());
  program::GcodeText refused;
  program::write_program_layer(refused, L);
  EXPECT_TRUE(refused.fault);
}

// Lines as the reader splits them (a last line without its end counts, an empty end does
// not), and the G lines among them (the reservation for the moves).
TEST(ReadProgram, LinesAndGLinesCounted) {
  struct Case {
    const char* text;
    std::size_t lines, g_lines;
  };
  for (const Case& c : {Case{"", 0, 0}, Case{"G1", 1, 1}, Case{"G1\n", 1, 1}, Case{"\n\n", 2, 0},
                        Case{"g1 X1\r\nM83\nG1 Y2", 3, 2}, Case{";G1\n G1\nG", 3, 1}}) {
    const GcodeLineCount n = count_gcode_lines(c.text);
    EXPECT_EQ(n.lines, c.lines) << c.text;
    EXPECT_EQ(n.g_lines, c.g_lines) << c.text;
    EXPECT_EQ(read_gcode_program(c.text).lines.size(), c.lines) << c.text;
  }
}

// Read a piece at a time (the start, two layers at a time, the end), a file gives the lines,
// moves, problems and figures the whole reading gives: the same kinds and values, the moves
// indexed within their piece, the pieces' first lines where they are in the file.
TEST(ReadProgram, PiecesReadAsTheWholeFile) {
  std::string layers;
  for (int k = 3; k <= 7; ++k) {
    const std::string z = std::to_string(0.2 * k);
    layers += ";LAYER_CHANGE\n;Z:" + z + "\n;HEIGHT:0.2\nG1 Z" + z + " F720\n" +
              ";TYPE:Solid infill\nG1 X" + std::to_string(10 + k) + " Y20 E0.5\n";
    if (k == 5) layers += "G2 X1 Y1 I1 J1\n";  // a problem, in the third piece
  }
  const std::string text = kPrusaStart + kPrint + layers + kEnd;
  const GcodeProgram whole = read_gcode_program(text);
  GcodePieceReader reader(text);
  ASSERT_EQ(reader.layer_count(), 7u);
  std::vector<GcodePieceReader::Piece> pieces;
  std::size_t line = 0, move = 0, problem = 0;
  while (reader.next(2)) {
    const GcodeProgram& p = reader.program();
    pieces.push_back(reader.piece());
    EXPECT_EQ(reader.first_line(), line);
    EXPECT_EQ(p.print_begin, whole.print_begin);
    EXPECT_EQ(p.print_end, whole.print_end);
    for (const GcodeLine& l : p.lines) {
      const GcodeLine& w = whole.lines[line++];
      EXPECT_EQ(l.raw, w.raw);
      EXPECT_EQ(l.kind, w.kind) << l.raw;
      EXPECT_EQ(l.value, w.value) << l.raw;
      EXPECT_EQ(l.layer, w.layer) << l.raw;
      if (l.kind != Kind::move) continue;
      ASSERT_EQ(w.move, static_cast<int>(move++)) << l.raw;
      const GcodeMove& a = p.moves.at(static_cast<std::size_t>(l.move));
      const GcodeMove& b = whole.moves[static_cast<std::size_t>(w.move)];
      EXPECT_EQ(a.from, b.from) << l.raw;
      EXPECT_EQ(a.to, b.to) << l.raw;
      EXPECT_EQ(a.de, b.de) << l.raw;
      EXPECT_EQ(a.type, b.type) << l.raw;
      EXPECT_EQ(a.height, b.height) << l.raw;
      EXPECT_EQ(a.line, b.line) << l.raw;
    }
    EXPECT_EQ(p.moves.size(), static_cast<std::size_t>(std::count_if(
                                  p.lines.begin(), p.lines.end(),
                                  [](const GcodeLine& l) { return l.kind == Kind::move; })));
    for (const GcodeProblem& q : p.problems) EXPECT_EQ(q.line, whole.problems.at(problem++).line);
    if (reader.piece() != GcodePieceReader::Piece::start) {
      EXPECT_EQ(p.at_print.e, whole.at_print.e);
      EXPECT_EQ(p.at_print.relative_e, whole.at_print.relative_e);
    }
  }
  EXPECT_EQ(line, whole.lines.size());
  EXPECT_EQ(move, whole.moves.size());
  EXPECT_EQ(problem, whole.problems.size());
  ASSERT_EQ(problem, 2u);  // the start's G28 (home), the arc
  using P = GcodePieceReader::Piece;
  EXPECT_EQ(pieces, (std::vector<P>{P::start, P::layers, P::layers, P::layers, P::layers, P::end}));
  const GcodeProgram& last = reader.program();
  EXPECT_EQ(last.layer_z, whole.layer_z);
  EXPECT_EQ(last.layer_height, whole.layer_height);
  EXPECT_EQ(last.at_end.e, whole.at_end.e);
  EXPECT_EQ(last.retraction.length, whole.retraction.length);
  EXPECT_FALSE(reader.next(2));
}

// What the reader still views (GcodePieceReader::held_from): the piece's first line, or
// earlier the ;TYPE: in force, which the moves of a piece without one of its own view; the
// text before it may go (map_foreign_gcode_consuming).
TEST(ReadProgram, APieceHoldsItsLinesAndTheTypeInForce) {
  std::string layers;
  for (int k = 3; k <= 8; ++k) {
    const std::string z = std::to_string(0.2 * k);
    layers += ";LAYER_CHANGE\n;Z:" + z + "\n;HEIGHT:0.2\nG1 Z" + z + " F720\n";
    if (k == 7) layers += ";TYPE:Solid infill\n";  // layers 5 and 6 keep the kPrint's last
    layers += "G1 X" + std::to_string(10 + k) + " Y20 E0.5\n";
  }
  const std::string text = kPrusaStart + kPrint + layers + kEnd;
  const std::size_t top = text.find(";TYPE:Top solid infill") + 6;
  const std::size_t solid = text.find(";TYPE:Solid infill") + 6;
  GcodePieceReader reader(text);
  std::vector<std::size_t> held, first;
  while (reader.next(1)) {
    const GcodeProgram& p = reader.program();
    held.push_back(reader.held_from());
    first.push_back(p.lines.empty()
                        ? text.size()
                        : static_cast<std::size_t>(p.lines[0].raw.data() - text.data()));
    if (reader.piece() != GcodePieceReader::Piece::layers) continue;
    for (const GcodeMove& m : p.moves) {
      if (!m.extruding()) continue;
      EXPECT_LE(held.back(), static_cast<std::size_t>(m.type.data() - text.data()));
    }
  }
  // start, kPrint's two layers, layers 3 to 8, the end.
  ASSERT_EQ(held.size(), 10u);
  EXPECT_EQ(held[0], 0u);        // no type yet
  EXPECT_EQ(held[1], first[1]);  // its own ;TYPE: comes after its first line
  EXPECT_EQ(held[2], first[2]);
  for (std::size_t k = 3; k <= 6; ++k) EXPECT_EQ(held[k], top) << k;  // layers 3 to 6
  EXPECT_LT(held[6], first[6]);
  EXPECT_EQ(held[7], first[7]);  // layer 7's own ;TYPE:
  EXPECT_EQ(held[8], solid);
  EXPECT_EQ(held[9], first[9]);  // the end begins with its ;TYPE:Custom
}

// A file without layers is one start piece (the whole file), an empty end, and no more.
TEST(ReadProgram, PiecesOfAFileWithoutLayers) {
  GcodePieceReader reader(kPrusaStart);
  EXPECT_EQ(reader.layer_count(), 0u);
  ASSERT_TRUE(reader.next(64));
  EXPECT_EQ(reader.piece(), GcodePieceReader::Piece::start);
  EXPECT_EQ(reader.program().lines.size(), read_gcode_program(kPrusaStart).lines.size());
  ASSERT_TRUE(reader.next(64));
  EXPECT_EQ(reader.piece(), GcodePieceReader::Piece::end);
  EXPECT_TRUE(reader.program().lines.empty());
  EXPECT_FALSE(reader.next(64));
}

}  // namespace
}  // namespace nonplanar
