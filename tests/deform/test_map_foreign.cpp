// map_foreign_gcode (src/deform/map_foreign_gcode.cpp): a planar G-code file of the normalised
// mesh, here written by our own planar engine, mapped back onto the curved layers must print
// as well as the built-in route; what it cannot map is refused with its line.
#include <gtest/gtest.h>

#include "nonplanar/check.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/patch_fit.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

CheckFigures figures(const std::string& gcode, const TriangleMesh& mesh) {
  auto moves = read_gcode_moves(gcode);
  EXPECT_TRUE(moves) << moves.error().message;
  auto f = check_print(*moves, &mesh, {}, {});
  EXPECT_TRUE(f);
  return *f;
}

// The saddle's plan, and a planar file of its normalised mesh from our own planar engine.
struct NormalisedSaddle {
  PrintConfig c;
  TriangleMesh mesh;
  SliceJob job;
  LayerPlan plan;
  std::string planar;
  NormalisedSaddle() {
    c.paths.fill_density = 1.0;
    mesh = test::placed(test::saddle(), c);
    job = make_job(c);
    auto a = analyze(mesh, job.analysis, {});
    std::vector<int> ids;
    auto fits = fit_patches(mesh, *a, job.fit, {}, &ids, {});
    plan = *plan_layers(mesh, *a, *fits, ids, job.layers, {});
    auto n = normalize_mesh(mesh, *plan.field, {}, {});
    auto paths = make_toolpaths(*slice_mesh(n->mesh, c.slice, {}), c.paths, {});
    planar = *make_gcode(*paths, c, {}, {});
  }
};

TEST(MapForeignGcode, PlanarFileOfTheNormalisedSaddlePrintsLikeTheBuiltInRoute) {
  const NormalisedSaddle saddle;
  const PrintConfig& c = saddle.c;
  const TriangleMesh& mesh = saddle.mesh;
  const SliceJob& job = saddle.job;
  const LayerPlan* plan = &saddle.plan;
  ASSERT_EQ(plan->stacks.size(), 1u);

  auto mapped = map_foreign_gcode(saddle.planar, *plan->field, {}, {});
  ASSERT_TRUE(mapped) << mapped.error().message;
  const std::string mapped_text = mapped->text();  // the moves read below view it
  const CheckFigures f = figures(mapped_text, mesh);
  EXPECT_LE(f.deviation_p95, 0.02);
  EXPECT_GT(f.covered_samples, 0.95 * static_cast<double>(f.surface_samples));
  EXPECT_EQ(f.collisions, 0u);
  EXPECT_LE(f.steepest_deg, job.layers.max_angle_deg + 0.5);
  EXPECT_GE(f.thickness_min, job.layers.min_layer_height - 1e-3);
  EXPECT_LE(f.thickness_max, job.layers.max_layer_height + 1e-3);
  EXPECT_NEAR(f.volume_ratio, 1.0, 0.03);
  // Top skins low to high (DESIGN.md §3): in each layer's top-skin run, every stroke
  // starts at its low end and no stroke lies lower than the one before it.
  auto moves = read_gcode_moves(mapped_text);
  ASSERT_TRUE(moves);
  std::size_t strokes = 0;
  int layer = -2;
  double prev_mean = -1e9;
  std::vector<Vec3> stroke;
  auto close = [&] {
    if (stroke.empty()) return;
    double z = 0;
    for (const Vec3& v : stroke) z += v.z();
    z /= static_cast<double>(stroke.size());
    EXPECT_LE(stroke.front().z(), stroke.back().z() + 2e-3) << "layer " << layer;
    EXPECT_GE(z, prev_mean - 2e-3) << "layer " << layer;  // µm rounding of the file
    prev_mean = z, ++strokes;
    stroke.clear();
  };
  for (const PrintMove& m : *moves) {
    if (m.layer != layer || m.type != "Top solid infill") close();
    if (m.layer != layer) layer = m.layer, prev_mean = -1e9;
    if (m.type != "Top solid infill") continue;
    if (!m.extruding) {
      if ((m.to - m.from).head<2>().norm() > 1e-9) close();
      continue;
    }
    if (stroke.empty()) stroke.push_back(m.from);
    stroke.push_back(m.to);
  }
  close();
  EXPECT_GT(strokes, 20u);
  // The built-in route on the same part, for comparison: the same layers, so nearly the same
  // volume and deviation.
  auto builtin = slice_model(mesh, job, {});
  ASSERT_TRUE(builtin);
  auto text = make_gcode(builtin->layers, c, {}, {});
  ASSERT_TRUE(text);
  const CheckFigures g = figures(*text, mesh);
  EXPECT_NEAR(f.volume_ratio, g.volume_ratio, 0.01);
  EXPECT_NEAR(f.deviation_p95, g.deviation_p95, 0.005);
  // The paths handed to the safety check carry the mapped thickness.
  double hmin = 1e9, hmax = 0;
  for (std::size_t li = 1; li < mapped->layers.size(); ++li)
    for (const ExtrusionPath& p : mapped->layers[li].paths)
      for (double h : p.height) hmin = std::min(hmin, h), hmax = std::max(hmax, h);
  EXPECT_GE(hmin, job.layers.min_layer_height - 1e-3);
  EXPECT_LE(hmax, job.layers.max_layer_height + 1e-3);
  EXPECT_LT(hmin, 0.19);  // some layers really are thinner than planar ...
  EXPECT_GT(hmax, 0.21);  // ... and some thicker
}

// Keeps every layer whole: a clip that changes nothing, which has the layers mapped one at a
// time, in order.
class KeepAll final : public LayerClip {
 public:
  Cover cover(double) const override { return Cover::all; }
  double margin(double, double, double) const override { return 1; }
};

// With nothing clipped the layers are mapped side by side before they are written, a window
// of 7 layers at a time here (each window's moves' paths the only ones held); the file, the
// gate's paths and a refusal past most_points (its line) are what mapping them one at a time
// gives.
TEST(MapForeignGcode, LayersMappedSideBySideWriteWhatOneAtATimeDoes) {
  const NormalisedSaddle saddle;
  const KeepAll keep_all;
  ForeignMapOptions in_order, windows;
  in_order.clip = &keep_all;
  windows.layers_at_once = 7;
  auto a = map_foreign_gcode(saddle.planar, *saddle.plan.field, {}, {}, windows);
  auto b = map_foreign_gcode(saddle.planar, *saddle.plan.field, {}, {}, in_order);
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(a->text() == b->text());  // (not EXPECT_EQ: the whole file)
  ASSERT_EQ(a->layers.size(), b->layers.size());
  ASSERT_GT(a->layers.size(), 3 * windows.layers_at_once);
  std::size_t points = 0;
  for (std::size_t i = 0; i < a->layers.size(); ++i) {
    ASSERT_EQ(a->layers[i].paths.size(), b->layers[i].paths.size());
    for (std::size_t k = 0; k < a->layers[i].paths.size(); ++k) {
      EXPECT_EQ(a->layers[i].paths[k].points, b->layers[i].paths[k].points);
      points += a->layers[i].paths[k].points.size();
    }
  }
  ASSERT_GT(points, 4000u);
  MapBackParams few;
  few.most_points = points / 2;
  auto c = map_foreign_gcode(saddle.planar, *saddle.plan.field, few, {}, windows);
  auto d = map_foreign_gcode(saddle.planar, *saddle.plan.field, few, {}, in_order);
  ASSERT_FALSE(c);
  ASSERT_FALSE(d);
  EXPECT_EQ(c.error().message, d.error().message);
  EXPECT_NE(c.error().message.find("mapped points"), std::string::npos) << c.error().message;
}

// The consuming form hands back the pages of what it has read as it goes (one layer at a time
// here) and writes what reading the text whole does: also where one ;TYPE: at the start is in
// force through the whole file (its moves view that line, which must not go).
TEST(MapForeignGcode, ConsumingTheTextWritesWhatReadingItDoes) {
  const NormalisedSaddle saddle;
  // (After a long start, so that the ;TYPE: line is on a page of its own that could go.)
  std::string one_type;
  for (int i = 0; i < 1000; ++i) one_type += "; a long start G-code\n";
  bool typed = false;
  for (std::size_t at = 0; at < saddle.planar.size();) {
    std::size_t end = saddle.planar.find('\n', at);
    end = end == std::string::npos ? saddle.planar.size() : end + 1;
    const std::string_view l(saddle.planar.data() + at, end - at);
    if (l.rfind(";TYPE:", 0) != 0)
      one_type += l;
    else if (!typed && l.rfind(";TYPE:Custom", 0) != 0)
      one_type += ";TYPE:Perimeter\n", typed = true;
    at = end;
  }
  ASSERT_TRUE(typed);
  ASSERT_GT(one_type.size(), 40 * 4096u);
  ForeignMapOptions windows;
  windows.layers_at_once = 1;
  for (const std::string* text : {&saddle.planar, static_cast<const std::string*>(&one_type)}) {
    auto a = map_foreign_gcode(*text, *saddle.plan.field, {}, {}, windows);
    auto b = map_foreign_gcode_consuming(std::string(*text), *saddle.plan.field, {}, {}, windows);
    ASSERT_TRUE(a && b);
    EXPECT_TRUE(a->text() == b->text());
    ASSERT_EQ(a->layers.size(), b->layers.size());
    ASSERT_GT(a->layers.size(), 20u);
    std::size_t perimeters = 0;
    for (std::size_t i = 0; i < a->layers.size(); ++i) {
      ASSERT_EQ(a->layers[i].paths.size(), b->layers[i].paths.size());
      for (std::size_t k = 0; k < a->layers[i].paths.size(); ++k) {
        EXPECT_EQ(a->layers[i].paths[k].role, b->layers[i].paths[k].role);
        EXPECT_EQ(a->layers[i].paths[k].points, b->layers[i].paths[k].points);
        perimeters += a->layers[i].paths[k].role == ExtrusionRole::perimeter;
      }
    }
    // With one type, every path is a perimeter (a view read as zeros would be solid infill).
    if (text == &one_type) {
      std::size_t paths = 0;
      for (const LayerToolpaths& L : a->layers) paths += L.paths.size();
      EXPECT_EQ(perimeters, paths);
      EXPECT_GT(paths, 50u);
    }
  }
}

// Paths given by before_layer go between the file's layers, each a layer of its own: the
// file's retractions still balance (the filament pulled back for the travel to them is owed to
// the file's next E), the filament pushed is the file's and theirs, and the nozzle, waiting
// over them after the last, comes down only where the file's next move in X or Y goes. In
// absolute and in relative E.
TEST(MapForeignGcode, PathsInsertedBetweenLayersKeepTheFilesFilament) {
  for (const bool relative : {false, true}) {
    PrintConfig c;
    c.gcode.relative_e = relative;
    const TriangleMesh box = test::placed(test::box(Vec3(0, 0, 0), Vec3(10, 10, 2)), c);
    auto paths = make_toolpaths(*slice_mesh(box, c.slice, {}), c.paths, {});
    ASSERT_TRUE(paths);
    const std::string planar = *make_gcode(*paths, c, {}, {});
    const auto field = planar_field({});
    // A path over the box's middle, before layer 4 (0.8 … 1.0 mm) and rising over its top, as a
    // shell's piece may (by s⁻): the layer change after it would go down into it.
    const Vec3 mid = 0.5 * (bounding_box(box).min + bounding_box(box).max);
    LayerToolpaths piece;
    ExtrusionPath p;
    p.role = ExtrusionRole::top_solid_infill, p.width = 0.45, p.speed = 20;
    p.points = {Vec3(mid.x() - 3, mid.y(), 1.0), Vec3(mid.x() + 3, mid.y(), 1.05)};
    p.height = {0.2, 0.25};
    piece.paths = {p};
    piece.z = piece.max_z = 1.05, piece.height = 0.2, piece.nonplanar = true;
    ForeignMapOptions opt;
    int calls = 0;
    opt.before_layer = [&](double z, const Vec3&) {
      ++calls;
      return std::abs(z - 1.0) < 1e-6 ? std::vector<LayerToolpaths>{piece}
                                      : std::vector<LayerToolpaths>{};
    };
    opt.filament_per_mm = [&](double w, double h) { return filament_per_mm(w, h, c.gcode); };
    auto plain = map_foreign_gcode(planar, *field, {}, {}, {});
    auto with = map_foreign_gcode(planar, *field, {}, {}, opt);
    ASSERT_TRUE(plain && with);
    const std::size_t n = plain->layers.size();
    EXPECT_EQ(calls, static_cast<int>(n) + 1);  // before each layer, and after the last
    ASSERT_EQ(with->layers.size(), n + 1);
    ASSERT_EQ(with->inserted.size(), n + 1);
    EXPECT_EQ(std::count(with->inserted.begin(), with->inserted.end(), 1), 1);
    EXPECT_EQ(with->inserted[4], 1);  // after layers 0-3 (tops 0.2 … 0.8)
    EXPECT_EQ(with->layers[4].paths.size(), 1u);
    const std::string a = plain->text(), b = with->text();
    auto count = [](const std::string& t, const std::string& w) {
      std::size_t k = 0;
      for (auto at = t.find(w); at != std::string::npos; at = t.find(w, at + 1)) ++k;
      return k;
    };
    EXPECT_EQ(count(b, ";LAYER_CHANGE"), count(a, ";LAYER_CHANGE") + 1);
    const GcodeProgram pa = read_gcode_program(a), pb = read_gcode_program(b);
    auto net = [](const GcodeProgram& g) {
      double e = 0;
      for (const GcodeMove& m : g.moves) e += m.de;
      return e;
    };
    const double len = (p.points[1] - p.points[0]).norm();
    const double want = len * filament_per_mm(0.45, 0.225, c.gcode);
    EXPECT_NEAR(net(pb) - net(pa), want, 1e-3) << (relative ? "relative" : "absolute");
    // After the path's last point, nothing goes below its top within 1 mm of it before a move
    // in X or Y has taken the nozzle away.
    std::size_t k = 0;
    while (k < pb.moves.size() && !(pb.moves[k].extruding() && pb.moves[k].to.z() > 1.04)) ++k;
    ASSERT_LT(k, pb.moves.size());
    for (++k; k < pb.moves.size(); ++k) {
      const GcodeMove& m = pb.moves[k];
      if ((m.to.head<2>() - p.points[1].head<2>()).norm() > 1.0) break;
      EXPECT_GE(m.to.z(), 1.05 - 1e-6) << "line " << m.line;
    }
  }
}

TEST(MapForeignGcode, RefusesWhatItCannotMapNamingTheLine) {
  const auto field = planar_field({});
  const std::string head = "M82\nG28\n;LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 X1 Y1 E1\n";
  auto arc = map_foreign_gcode(head + "G2 X5 Y5 I1 J1 E2\n", *field, {}, {});
  ASSERT_FALSE(arc);
  EXPECT_NE(arc.error().message.find("line 7: arc"), std::string::npos) << arc.error().message;
  auto home = map_foreign_gcode(head + "G1 X2 Y2 E2\nG29\n", *field, {}, {});
  ASSERT_FALSE(home);
  EXPECT_NE(home.error().message.find("line 8"), std::string::npos) << home.error().message;
  auto word = map_foreign_gcode(head + "G1 X2 Q4\n", *field, {}, {});
  ASSERT_FALSE(word);
  EXPECT_NE(word.error().message.find("line 7"), std::string::npos);
  EXPECT_FALSE(map_foreign_gcode("G1 X1 Y1 E1\n", *field, {}, {}));  // no layers
  // A start G-code that leaves the nozzle 2.5e12 mm away (found by the fuzzer: the travel
  // back was sampled every 0.1 mm into an int).
  auto far = map_foreign_gcode("G1 X2555555555555 Y0\n" + head.substr(4), *field, {}, {});
  ASSERT_FALSE(far);
  EXPECT_NE(far.error().message.find("line 6: coordinate beyond 10 m"), std::string::npos)
      << far.error().message;
  // Start G-code before the first layer passes untouched, whatever it holds.
  auto ok = map_foreign_gcode("M862.3 P \"MK3S\"\nG29 ; mesh\n" + head.substr(8) + "G92 E0\n",
                              *field, {}, {});
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_EQ(ok->text().rfind("M862.3 P \"MK3S\"\nG29 ; mesh\n", 0), 0u);
  EXPECT_NE(ok->text().find("G1 X1.000 Y1.000 E1.00000"), std::string::npos) << ok->text();
  // Relative XYZ inside the print is applied here: the mapped moves are absolute. G91 makes
  // E relative too (hostile input #4: read as absolute, it over-extruded 75x on a dome).
  auto rel = map_foreign_gcode(head + "G91\nG1 X2 Y1 E0.5\nG90\nG1 X5 E2\n", *field, {}, {});
  ASSERT_TRUE(rel) << rel.error().message;
  EXPECT_NE(rel->text().find("G1 X3.000 Y2.000 E1.50000"), std::string::npos) << rel->text();
  EXPECT_NE(rel->text().find("G1 X5.000 Y2.000 E2.00000"), std::string::npos) << rel->text();
  EXPECT_EQ(rel->text().find("\nG91\n"), std::string::npos);
  // M83 mid-print: the E that follows is relative, in the file and in what is written.
  auto m83 = map_foreign_gcode(head + "G1 X2 Y1 E2\nM83\nG1 X3 Y1 E0.5\nM82\nG1 X4 Y1 E3\n", *field,
                               {}, {});
  ASSERT_TRUE(m83) << m83.error().message;
  const std::string t = m83->text();
  EXPECT_NE(t.find("M83\nG1 X3.000 Y1.000 E0.50000"), std::string::npos) << t;
  EXPECT_NE(t.find("G1 X4.000 Y1.000 E3.00000"), std::string::npos) << t;
}

}  // namespace
}  // namespace nonplanar
