// End-to-end planar prints, read back by the strict test reader.
#include <gtest/gtest.h>

#include <cmath>

#include "core/column_caster.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/toolhead.hpp"
#include "support/files.hpp"
#include "support/gcode_reader.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

struct Printed {
  TriangleMesh mesh;
  test::Program prog;
  std::string text;
};

Printed print(TriangleMesh mesh, const PrintConfig& c) {
  // Place as the loader does: centre on the bed, lowest point at 0.
  const BoundingBox b = bounding_box(mesh);
  const Vec3 shift(c.bed_center().x() - 0.5 * (b.min.x() + b.max.x()),
                   c.bed_center().y() - 0.5 * (b.min.y() + b.max.y()), -b.min.z());
  for (Vec3& v : mesh.vertices) v += shift;
  auto layers = slice_mesh(mesh, c.slice, {});
  EXPECT_TRUE(layers);
  auto paths = make_toolpaths(*layers, c.paths, {});
  EXPECT_TRUE(paths);
  auto text = make_gcode(*paths, c, {"test"}, {});
  EXPECT_TRUE(text);
  Printed p{std::move(mesh), test::read_gcode(*text), *text};
  EXPECT_EQ(p.prog.error, "");
  return p;
}

double filament_volume(const test::Program& prog, double d, bool skip_skirt = true) {
  double e = 0;
  for (const auto& m : prog.moves)
    if (m.layer >= 0 && !m.travel && !(skip_skirt && m.type == "Skirt/Brim")) e += m.de;
  return e * M_PI * 0.25 * d * d;
}

// A layer printed after a higher one (a shell's piece after core layers that rise above it)
// travels over what was laid before, not through it at its own height + the lift: the
// bunny's shells had gone through their core that way, which the collision search now sees.
TEST(PlanarPrint, ATravelClearsHigherMaterialLaidBefore) {
  PrintConfig c;
  auto line = [](const Vec3& a, const Vec3& b, double h) {
    ExtrusionPath p;
    p.points = {a, b}, p.height = {h, h}, p.role = ExtrusionRole::perimeter;
    return p;
  };
  std::vector<LayerToolpaths> layers(2);
  for (int k = 0; k < 25; ++k) {  // a wall 5 mm high across the way, printed first
    LayerToolpaths& w = layers[0];
    const double z = 0.2 * (k + 1);
    w.paths.push_back(line({110, 100, z}, {110, 120, z}, 0.2));
    w.z = w.max_z = z;
  }
  layers[0].nonplanar = true;
  LayerToolpaths& low = layers[1];  // then two lines at z = 1, one each side of it
  low.paths = {line({100, 110, 1}, {102, 110, 1}, 0.2), line({118, 110, 1}, {120, 110, 1}, 0.2)};
  low.z = low.max_z = 1, low.nonplanar = true;
  auto text = make_gcode(layers, c, {"test"}, {});
  ASSERT_TRUE(text) << text.error().message;
  auto moves = read_gcode_moves(*text);
  ASSERT_TRUE(moves);
  double over = 0;
  for (const PrintMove& m : *moves)
    if (!m.extruding && m.layer == 1 && (m.from.x() - 110) * (m.to.x() - 110) < 0)
      over = std::max(over, m.from.z());
  EXPECT_GE(over, 5.0 + travel_lift(c.gcode.retract_lift) - 1e-6);
  EXPECT_EQ(find_collisions(*moves, check_params(c, 30), nullptr, {})->collisions, 0u);
}

// F is modal: an extrusion's feed rate is written where its path's moves begin and where its
// speed changes, and every move of a path is printed at its path's speed.
TEST(PlanarPrint, FeedRateIsWrittenWhereAPathBeginsOrItsSpeedChanges) {
  PrintConfig c;
  auto path = [](double y, double speed) {
    ExtrusionPath p;
    p.role = ExtrusionRole::perimeter, p.speed = speed;
    for (int k = 0; k <= 4; ++k)
      p.points.emplace_back(100 + 2 * k, y, 0.2), p.height.push_back(0.2);
    return p;
  };
  std::vector<LayerToolpaths> layers(2);
  layers[0].z = layers[0].max_z = 0.2;
  layers[0].paths = {path(100, 15), path(102, 15)};
  layers[1].z = layers[1].max_z = 0.4;
  layers[1].paths = {path(100, 30), path(102, 45)};
  for (ExtrusionPath& p : layers[1].paths)
    for (Vec3& v : p.points) v.z() = 0.4;
  auto text = make_gcode(layers, c, {"test"}, {});
  ASSERT_TRUE(text) << text.error().message;
  const GcodeProgram prog = read_gcode_program(*text);
  std::vector<double> feeds, own;
  for (const GcodeMove& m : prog.moves)
    if (m.layer >= 0 && m.extruding() && m.type != "Skirt/Brim")
      feeds.push_back(m.feed), own.push_back(m.f);
  ASSERT_EQ(feeds.size(), 16u);
  for (std::size_t k = 0; k < 16; ++k) {
    const double speed = k < 8 ? 15 : k < 12 ? 30 : 45;
    EXPECT_EQ(feeds[k], 60 * speed) << k;
    EXPECT_EQ(std::isnan(own[k]), k % 4 != 0) << k;  // each path's first move only
  }
}

TEST(PlanarPrint, CubeAtFullInfillExtrudesItsVolume) {
  PrintConfig c;
  c.paths.fill_density = 1.0;
  const Printed p = print(test::box({0, 0, 0}, {20, 20, 20}), c);
  const double ratio = filament_volume(p.prog, c.gcode.filament_diameter) / 8000.0;
  EXPECT_NEAR(ratio, 1.0, 0.03);
  ASSERT_EQ(p.prog.layer_z.size(), 100u);
  EXPECT_NEAR(p.prog.layer_z.front(), 0.2, 1e-9);
  EXPECT_NEAR(p.prog.layer_z.back(), 20.0, 1e-9);
  // Perimeters per layer: extrusion runs typed perimeter, counted between travels.
  for (int layer = 0; layer < 100; layer += 9) {
    int loops = 0;
    bool in = false;
    for (const auto& m : p.prog.moves) {
      if (m.layer != layer) continue;
      const bool per = !m.travel && (m.type == "Perimeter" || m.type == "External perimeter");
      if (per && !in) ++loops;
      in = per || (in && !m.travel);
      if (m.travel && std::hypot(m.to.x() - m.from.x(), m.to.y() - m.from.y()) > 1e-9) in = false;
    }
    EXPECT_EQ(loops, c.paths.perimeters) << "layer " << layer;
  }
}

TEST(PlanarPrint, CylinderOuterPerimeterIsRMinusHalfWidth) {
  PrintConfig c;
  const double R = 10;
  // 256-gon prism: the chord error (0.00075 mm) is far below the 0.01 mm tolerance.
  TriangleMesh cyl;
  const int n = 256;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    cyl.vertices.emplace_back(R * std::cos(a), R * std::sin(a), 0);
    cyl.vertices.emplace_back(R * std::cos(a), R * std::sin(a), 6);
  }
  cyl.vertices.emplace_back(0, 0, 0);
  cyl.vertices.emplace_back(0, 0, 6);
  const int cb = 2 * n, ct = 2 * n + 1;
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    cyl.faces.push_back({2 * i, 2 * j, 2 * j + 1});
    cyl.faces.push_back({2 * i, 2 * j + 1, 2 * i + 1});
    cyl.faces.push_back({cb, 2 * j, 2 * i});
    cyl.faces.push_back({ct, 2 * i + 1, 2 * j + 1});
  }
  ASSERT_NEAR(signed_volume(cyl), M_PI * R * R * 6, 1.0);
  const Printed q = print(cyl, c);
  const Vec2 centre = c.bed_center();
  int checked = 0;
  for (const auto& m : q.prog.moves) {
    if (m.travel || m.type != "External perimeter") continue;
    const double w = m.layer == 0 ? c.paths.first_layer_width : c.paths.external_perimeter_width;
    EXPECT_NEAR((m.to.head<2>() - centre).norm(), R - w / 2, 0.01) << "layer " << m.layer;
    ++checked;
  }
  EXPECT_GT(checked, 30 * 50);  // every layer's loop (collinear vertices are merged)
}

TEST(PlanarPrint, LongTravelsAreRetractedAndRestored) {
  PrintConfig c;
  TriangleMesh two = test::box({0, 0, 0}, {10, 10, 3});
  test::append(two, test::box({30, 0, 0}, {40, 10, 3}));
  const Printed p = print(two, c);
  int long_travels = 0;
  const auto& mv = p.prog.moves;
  for (std::size_t i = 0; i < mv.size(); ++i) {
    const double d = (mv[i].to.head<2>() - mv[i].from.head<2>()).norm();
    if (!mv[i].travel || mv[i].de != 0 || d <= c.gcode.retract_before_travel || mv[i].layer < 0)
      continue;
    ++long_travels;
    // The last E move before it is a retraction; the first E move after it restores it.
    double before = 0, after = 0;
    for (std::size_t k = i; k-- > 0;)
      if (mv[k].de != 0) {
        before = mv[k].de;
        break;
      }
    for (std::size_t k = i + 1; k < mv.size(); ++k)
      if (mv[k].de != 0) {
        after = mv[k].de;
        break;
      }
    EXPECT_NEAR(before, -c.gcode.retract_length, 1e-9) << "line " << mv[i].line;
    EXPECT_NEAR(after, c.gcode.retract_length, 1e-9) << "line " << mv[i].line;
  }
  EXPECT_GT(long_travels, 15);  // at least one island hop per layer
}

TEST(PlanarPrint, EveryExtrusionLiesInsideTheMesh) {
  PrintConfig c;
  const TriangleMesh m = test::height_field_solid(
      [](double x, double y) { return 5 + 0.1 * x + 0.05 * y; }, 0, 20, 0, 15, 20, 15);
  const Printed p = print(m, c);
  const ColumnCaster cols(p.mesh);
  std::size_t total = 0, outside = 0;
  for (const auto& mv : p.prog.moves) {
    if (mv.travel || mv.layer < 0 || mv.type == "Skirt/Brim") continue;
    ++total;
    // The bead sits below the nozzle: test its middle.
    if (!cols.inside(mv.to.x(), mv.to.y(), mv.to.z() - 0.5 * mv.height)) ++outside;
  }
  EXPECT_GT(total, 1000u);
  EXPECT_EQ(outside, 0u);
}

TEST(PlanarPrint, PrusaSlicerIniReachesTheGcode) {
  auto c = load_config(std::filesystem::path(NONPLANAR_TEST_DATA) / "prusaslicer_015mm_215C.ini");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_NEAR(c->slice.layer_height, 0.15, 1e-12);
  EXPECT_EQ(c->paths.perimeters, 3);
  EXPECT_EQ(c->gcode.flavor, GcodeFlavor::reprapfirmware);
  EXPECT_EQ(c->bed_max, Vec2(200, 200));
  EXPECT_FALSE(c->notes.empty());  // "stars" infill is not supported: noted, grid used
  const Printed p = print(test::box({0, 0, 0}, {10, 10, 3}), *c);
  EXPECT_NE(p.text.find("M109 S215"), std::string::npos);
  EXPECT_NE(p.text.find("M140 S55"), std::string::npos);  // from the second layer on
  EXPECT_NE(p.text.find(";HEIGHT:0.150"), std::string::npos);
  EXPECT_NE(p.text.find("G28 ; home all axes"), std::string::npos);  // its start G-code
  EXPECT_NEAR(p.prog.layer_z[1] - p.prog.layer_z[0], 0.15, 1e-9);
}

// Hostile-input #6: a 215 mm part on the 220 mm bed got a skirt from X -3.75 to 223.75.
TEST(PlanarPrint, NothingLeavesTheBed) {
  PrintConfig c;
  TriangleMesh wide = test::box({0, 0, 0}, {215, 20, 1});
  const BoundingBox b = bounding_box(wide);
  for (Vec3& v : wide.vertices) v += Vec3(110 - 0.5 * b.max.x(), 100, 0);
  auto layers = slice_mesh(wide, c.slice, {});
  ASSERT_TRUE(layers);
  auto paths = make_toolpaths(*layers, c.paths, {});
  ASSERT_TRUE(paths);
  auto refused = make_gcode(*paths, c, {}, {});
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().status, Status::invalid_argument);
  EXPECT_NE(refused.error().message.find("the skirt reaches X"), std::string::npos)
      << refused.error().message;
  c.paths.skirts = 0;  // without it every move stays on the bed
  auto paths0 = make_toolpaths(*layers, c.paths, {});
  ASSERT_TRUE(paths0);
  auto ok = make_gcode(*paths0, c, {}, {});
  ASSERT_TRUE(ok) << ok.error().message;
  const test::Program prog = test::read_gcode(*ok);
  ASSERT_EQ(prog.error, "");
  for (const auto& m : prog.moves) {
    EXPECT_GE(m.to.x(), 0.0);
    EXPECT_LE(m.to.x(), 220.0);
  }
}

// Hostile-input #5: a comment that mentions M190 dropped our wait for the bed, and an
// unknown placeholder reached the printer raw.
TEST(PlanarPrint, CustomGcodeIsCheckedNotPassedRaw) {
  const Printed base = print(test::box({0, 0, 0}, {10, 10, 1}), PrintConfig{});
  auto start_of = [](const std::string& start) {
    PrintConfig c;
    c.gcode.start_gcode = start;
    return c;
  };
  const Printed commented =
      print(test::box({0, 0, 0}, {10, 10, 1}), start_of("G28 ; M190 and M109 come later\n"));
  EXPECT_NE(commented.text.find("\nM190 S60\n"), std::string::npos);
  EXPECT_NE(commented.text.find("\nM109 S215\n"), std::string::npos);
  const Printed own = print(test::box({0, 0, 0}, {10, 10, 1}), start_of("M190 S70\nG28\n"));
  EXPECT_EQ(own.text.find("M190 S60"), std::string::npos);  // the profile waits itself
  EXPECT_NE(own.text.find("M109 S215"), std::string::npos);
  // Macros are expanded (config/test_macros.cpp); what cannot be is refused, never sent raw.
  for (const char* bad : {"G28 ; {if x}\n", "G1 Z{max_layer_zz}\n", "M862.3 P \"[printer_mode]\"\n",
                          "{if layer_height<0.075}M221 S100{else}M221 S95\n"}) {
    auto r = check_custom_gcode(start_of(bad));
    ASSERT_FALSE(r) << bad;
    EXPECT_EQ(r.error().message.rfind("start_gcode: line 1: ", 0), 0u) << r.error().message;
  }
  PrintConfig end;
  end.gcode.end_gcode = "G1 X0 Y200 Z{max_layer_z+1}\n";
  ASSERT_TRUE(check_custom_gcode(end));
  const Printed lifted = print(test::box({0, 0, 0}, {10, 10, 1}), end);
  EXPECT_NE(lifted.text.find("\nG1 X0 Y200 Z2\n"), std::string::npos);  // 1 mm over the top
  // Found by the settings fuzzer: binary bytes in end_gcode went to the printer raw.
  end.gcode.end_gcode = "M104 S0\nM84 \xb7\xb7\n";
  auto binary = check_custom_gcode(end);
  ASSERT_FALSE(binary);
  EXPECT_EQ(binary.error().message, "end_gcode: line 2 holds a byte that is not printable ASCII");
  end.gcode.end_gcode =
      "M104 S0 ; 215 \xc2\xb0"
      "C\n" +
      std::string(300, ';') + "\n";
  auto long_line = check_custom_gcode(end);
  ASSERT_FALSE(long_line);
  EXPECT_EQ(long_line.error().message, "end_gcode: line 2 is longer than 255 characters");
  // Found by the settings fuzzer: a filament block's stray quote (an unbalanced ini list) went
  // into the print, and only the safety check read it back.
  PrintConfig quote;
  quote.gcode.end_filament_gcode = "; END gcode for filament\n\"\n";
  auto stray = check_custom_gcode(quote);
  ASSERT_FALSE(stray);
  EXPECT_EQ(stray.error().message, "end_filament_gcode: line 2: '\"' is not a G-code command");
  quote.gcode.end_filament_gcode.clear();
  quote.gcode.layer_gcode = ";AFTER_LAYER_CHANGE\n;[layer_z]\nM83\n";
  auto mode = check_custom_gcode(quote);
  ASSERT_FALSE(mode);
  EXPECT_EQ(
      mode.error().message,
      "layer_gcode: sets relative extrusion (M83) but use_relative_e_distances is 0 (layer 0)");
  quote.gcode.layer_gcode.clear();
  quote.gcode.start_filament_gcode = "M900 K0.05\nG1 X-50 Y10 F3000\n";
  auto far = check_custom_gcode(quote);
  ASSERT_FALSE(far);
  EXPECT_EQ(far.error().message.rfind("start_filament_gcode: line 2 goes to X-50.000", 0), 0u)
      << far.error().message;
  // The default purge on a 180 mm bed, given as text the way an old profile carries it.
  PrintConfig small = start_of(PrintConfig{}.gcode.start_gcode);
  small.bed_max = Vec2(180, 180);
  auto off = check_custom_gcode(small);
  ASSERT_FALSE(off);
  EXPECT_NE(off.error().message.find("line 5 goes to X2.000 Y200.000, off the bed"),
            std::string::npos)
      << off.error().message;
  EXPECT_NE(base.text.find("G1 Y200 E15 F1200 ; purge line"), std::string::npos);
}

// #16 item 7: cancel-object labels around each layer's part (not the skirt), as PrusaSlicer
// writes them: OctoPrint's comments, and the firmware's M486 or Klipper's EXCLUDE_OBJECT_*.
TEST(PlanarPrint, ObjectLabelsWrapEveryLayerOfThePart) {
  auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
      ++n;
    return n;
  };
  PrintConfig c;
  c.gcode.object_name = "box part.stl";
  ASSERT_TRUE(set_config_value(c, "gcode_label_objects", "firmware"));
  const Printed m = print(test::box({0, 0, 0}, {20, 10, 2}), c);
  const std::size_t layers = count(m.text, ";LAYER_CHANGE\n");
  ASSERT_EQ(layers, 10u);
  EXPECT_EQ(count(m.text, "\nM486 T1\n"), 1u);
  EXPECT_EQ(count(m.text, "\nM486 S0\n"), layers);
  EXPECT_EQ(count(m.text, "\nM486 S-1\n"), layers);
  EXPECT_EQ(count(m.text, "; printing object box part.stl id:0 copy 0\n"), layers);
  // The skirt is outside the label: the first layer's label opens after its skirt.
  const std::size_t skirt = m.text.find(";TYPE:Skirt/Brim"), open = m.text.find("M486 S0");
  EXPECT_LT(skirt, open);
  ASSERT_TRUE(set_config_value(c, "gcode_flavor", "klipper"));
  const Printed k = print(test::box({0, 0, 0}, {20, 10, 2}), c);
  EXPECT_EQ(count(k.text, "EXCLUDE_OBJECT_START NAME=box_part.stl_id_0_copy_0\n"), layers);
  EXPECT_EQ(count(k.text, "EXCLUDE_OBJECT_END NAME=box_part.stl_id_0_copy_0\n"), layers);
  EXPECT_EQ(count(k.text, "M486"), 0u);
  // The footprint: the 20 x 10 box at the bed's centre, its outer perimeter's centre line
  // half a width inside.
  const std::string def =
      "EXCLUDE_OBJECT_DEFINE NAME=box_part.stl_id_0_copy_0 CENTER=110.000,110.000 "
      "POLYGON=[[100.";
  EXPECT_NE(k.text.find(def), std::string::npos) << k.text.substr(0, 2000);
  for (const char* comments_only : {"octoprint", "1"}) {  // 2.6's and 2.5's (the MK3S's)
    ASSERT_TRUE(set_config_value(c, "gcode_label_objects", comments_only));
    const Printed o = print(test::box({0, 0, 0}, {20, 10, 2}), c);
    EXPECT_EQ(count(o.text, "EXCLUDE_OBJECT"), 0u);
    EXPECT_EQ(count(o.text, "; stop printing object box part.stl id:0 copy 0\n"), layers);
  }
  EXPECT_FALSE(set_config_value(c, "gcode_label_objects", "sometimes"));
}

TEST(Config, BadValuesNameTheKeyAndLine) {
  auto r = parse_ini_config("layer_height = 0.2\nfill_density = lots\n");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "line 2: fill_density: 'lots' is not a number or a percentage");
  auto j = parse_json_config(R"({"layer_height": -1})");
  ASSERT_FALSE(j);
  EXPECT_EQ(j.error().message.rfind("layer_height:", 0), 0u);
  EXPECT_FALSE(parse_ini_config("this line has no equals sign\n"));
  EXPECT_FALSE(parse_json_config("[1, 2]"));
  auto ok = parse_json_config(
      R"({"fill_density": "35%", "temperature": 230, "use_relative_e_distances": true})");
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_NEAR(ok->paths.fill_density, 0.35, 1e-12);
  EXPECT_TRUE(ok->gcode.relative_e);
}

}  // namespace
}  // namespace nonplanar
