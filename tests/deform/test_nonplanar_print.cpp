// The whole pipeline on analytic solids: figures that must hold (issue: end-to-end).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "layers/shell_plan.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/gcode.hpp"
#include "nonplanar/io.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

struct Outcome {
  SliceResult result;
  CheckFigures figures;
  std::string gcode;
};

Outcome run(const TriangleMesh& raw, PrintConfig c = {}, CheckParams cp = {}) {
  const TriangleMesh mesh = test::placed(raw, c);
  auto r = slice_model(mesh, make_job(c), {});
  EXPECT_TRUE(r) << r.error().message;
  auto text = make_gcode(r->layers, c, r->header, {});
  EXPECT_TRUE(text);
  auto moves = read_gcode_moves(*text);  // strict: any unknown command fails
  EXPECT_TRUE(moves) << moves.error().message;
  auto f = check_print(*moves, &mesh, cp, {});
  EXPECT_TRUE(f);
  return {std::move(*r), *f, std::move(*text)};
}

void expect_good(const Outcome& o, std::size_t stacks) {
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_EQ(o.result.plan.stacks.size(), stacks);
  EXPECT_TRUE(o.result.nonplanar);
  EXPECT_LE(o.figures.deviation_p95, 0.02);
  EXPECT_GT(o.figures.covered_samples, 0.95 * static_cast<double>(o.figures.surface_samples));
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_EQ(o.result.collisions, 0u);
  EXPECT_LE(o.result.steepest_deg, lp.max_angle_deg + 0.5);
  EXPECT_LE(o.figures.steepest_deg, lp.max_angle_deg + 0.5);
  EXPECT_GE(o.result.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.result.thickness_max, lp.max_layer_height + 1e-3);
  // ... and as `check` reads them back from the G-code alone.
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  EXPECT_LT(o.figures.outside_fraction, 0.01);
  for (const char* tag : {";TYPE:External perimeter", ";TYPE:Top solid infill", ";LAYER_CHANGE",
                          ";HEIGHT:", ";WIDTH:"})
    EXPECT_NE(o.gcode.find(tag), std::string::npos) << tag;
  EXPECT_EQ(o.gcode.find("G2 "), std::string::npos);  // never arcs
  EXPECT_EQ(o.gcode.find("G3 "), std::string::npos);
}

TEST(NonplanarPrint, Saddle) {
  expect_good(run(test::saddle()), 1);
}

TEST(NonplanarPrint, SineRoofAtFullInfillKeepsItsVolume) {
  PrintConfig c;
  c.paths.fill_density = 1.0;
  const Outcome o = run(test::sine_roof(), c);
  expect_good(o, 1);
  EXPECT_NEAR(o.figures.volume_ratio, 1.0, 0.03);
}

// Travels never pass through printed material: along every travel, no earlier extrusion
// within the nozzle tip's radius stands higher than the nozzle by more than h / 2 (the
// collision depth of DESIGN.md §3). Curved layers put lower and higher material side by
// side, so an unlifted travel over a wave would fail this.
TEST(NonplanarPrint, TravelsClearPrintedMaterial) {
  const Outcome o = run(test::height_field_solid(
      [](double x, double) { return 8 + 1.5 * std::sin(2 * M_PI * x / 25); }, 0, 50, 0, 30, 150,
      60));
  expect_good(o, 1);
  auto moves = read_gcode_moves(o.gcode);
  ASSERT_TRUE(moves);
  // Extrusion samples every 0.2 mm, binned in 1 mm cells.
  std::map<std::pair<int, int>, std::vector<Vec3>> deposit;
  auto cell = [](double v) { return static_cast<int>(std::floor(v)); };
  std::size_t travels = 0, lifted = 0;
  for (const PrintMove& m : *moves) {
    const double len = (m.to - m.from).head<2>().norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.2)));
    if (m.extruding) {
      for (int k = 0; k <= n; ++k) {
        const Vec3 p = m.from + (m.to - m.from) * (static_cast<double>(k) / n);
        deposit[{cell(p.x()), cell(p.y())}].push_back(p);
      }
      continue;
    }
    if (m.filament != 0 || len < 1e-6 || m.layer < 0) continue;
    ++travels;
    lifted += m.from.z() > 8 + 1.5 + 0.2;  // above the whole roof
    for (int k = 0; k <= n; ++k) {
      const Vec3 p = m.from + (m.to - m.from) * (static_cast<double>(k) / n);
      for (int a = cell(p.x()) - 1; a <= cell(p.x()) + 1; ++a)
        for (int b = cell(p.y()) - 1; b <= cell(p.y()) + 1; ++b) {
          const auto it = deposit.find({a, b});
          if (it == deposit.end()) continue;
          for (const Vec3& q : it->second) {
            if ((q - p).head<2>().norm() > 0.4) continue;
            ASSERT_LE(q.z() - p.z(), 0.1) << "travel at line " << m.line << " through material at ("
                                          << q.x() << ", " << q.y() << ", " << q.z() << ")";
          }
        }
    }
  }
  EXPECT_GT(travels, 100u);
  EXPECT_GT(lifted, 10u);  // the curved top layers' travels went over the roof
}

TEST(NonplanarPrint, TwoCurvedTowers) {
  expect_good(run(test::domed_towers()), 2);
}

TEST(NonplanarPrint, DomeCutByABox) {
  expect_good(run(test::dome_cut_by_box()), 1);
}

// A shared curved model whose fit swings off the patch (before the top was tamed there, the
// blend made a 0.024 mm layer and the patch fell back to planar). PrusaSlicer's planar
// p95 on it is 0.085 mm.
// The held-out dome at max_angle 20 (issue #21, item 7): its faceted top has a dip 0.25 mm
// wide and 0.015 mm deep beside the box's wall, off the middle of a chord over it. Layers
// crossed there 0.094 mm apart against h_min 0.1, while the gate read 0.106 at the points and
// check 0.078 from its plane fits. Counted here by brute force, wherever a layer's line
// crosses one of the layer before, they are at least h_min apart less the gate's slack; and
// slice's figures are check's to the digit.
TEST(NonplanarPrint, HeldOutDomeAt20DegreesCrossesNoCloserThanHMin) {
  const PrintConfig c;
  const TriangleMesh mesh = test::placed(test::dome_cut_by_box(), c);
  const SliceJob job = make_job(c, 20);
  auto r = slice_model(mesh, job, {});
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->plan.stacks.size(), 1u);
  auto moves = read_gcode_moves(r->gcode);
  ASSERT_TRUE(moves);
  auto f = check_print(*moves, nullptr, job.check, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->thickness_min, r->thickness_min);
  EXPECT_EQ(f->thickness_max, r->thickness_max);
  std::map<int, std::vector<const PrintMove*>> by_layer;
  for (const PrintMove& m : *moves)
    if (counted(m)) by_layer[m.layer].push_back(&m);
  double least = 1e300;
  std::size_t crossings = 0;
  for (auto up = std::next(by_layer.begin()); up != by_layer.end(); ++up)
    for (const PrintMove* s : up->second)
      for (const PrintMove* t : std::prev(up)->second) {
        const Vec2 d1 = (s->to - s->from).head<2>(), d2 = (t->to - t->from).head<2>();
        const Vec2 w = (t->from - s->from).head<2>();
        const double den = d1.x() * d2.y() - d1.y() * d2.x();
        if (std::abs(den) < 1e-12) continue;
        const double u = (w.x() * d2.y() - w.y() * d2.x()) / den;
        const double v = (w.x() * d1.y() - w.y() * d1.x()) / den;
        if (u < 0 || u > 1 || v < 0 || v > 1) continue;
        const double gap = s->from.z() + u * (s->to.z() - s->from.z()) - t->from.z() -
                           v * (t->to.z() - t->from.z());
        ++crossings;
        least = std::min(least, gap);
      }
  EXPECT_GT(crossings, 10000u);
  EXPECT_GE(least, job.layers.min_layer_height - job.gate.thickness_slack);
  EXPECT_GE(r->thickness_min, job.layers.min_layer_height - job.gate.thickness_slack);
}

TEST(NonplanarPrint, SharedFoilCutter) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_FoilCutter.stl", {}, {});
  ASSERT_TRUE(m);
  const Outcome o = run(m->mesh);
  expect_good(o, 1);
  EXPECT_GT(o.figures.deviation_p95, 0.0);
}

// A coarse mesh (1280 facets): the smooth fit through its vertices is 33° steep at the rim
// and up to 0.04 mm above the facets, so it fell back to planar (p95 0.077 mm). The stack's
// top now lies on the facets (layers/faceted_top.hpp), and its plane sits deep enough that
// the 30° layers at the rim are thick enough for the nozzle's flat.
TEST(NonplanarPrint, SharedSphereTopFollowsItsFacets) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_prusa_sphere.stl", {}, {});
  ASSERT_TRUE(m);
  const Outcome o = run(m->mesh);
  expect_good(o, 1);
  EXPECT_LE(o.figures.deviation_p95, 0.01);
}

// The same on a coarse sphere the test makes (1280 facets, 31 mm across).
TEST(NonplanarPrint, CoarseIcosphereTopFollowsItsFacets) {
  const Outcome o = run(test::icosphere({0, 0, 15.5}, 15.5, 3));
  expect_good(o, 1);
  EXPECT_LE(o.figures.deviation_p95, 0.01);
}

// A top that rises from near the bed: no stack over a plane can follow it, so it prints as a
// curved shell over a planar core (layers/shell_plan.hpp). The shell's lowest layer fills the
// core's stairs; at full infill the volume still comes out right.
TEST(NonplanarPrint, RibTopFromNearTheBedPrintsAsAShell) {
  PrintConfig c;
  c.paths.fill_density = 1.0;
  const Outcome o = run(test::rib(), c);
  expect_good(o, 0);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_LE(o.figures.deviation_p95, 0.005);
  EXPECT_NEAR(o.figures.volume_ratio, 1.0, 0.03);
  ASSERT_FALSE(o.result.notices.empty());
  EXPECT_NE(o.result.notices.back().text.find("curved shell"), std::string::npos);
}

// The rib with a taller tower 2 mm past its end, or against its side: the shell prints where
// nothing stands above it, and its points go between the tower's layers, near it close to
// their own height (layers/shell_region.hpp). Before, both parts went planar ("the part's
// highest point is not on the patches").
TEST(NonplanarPrint, RibBesideATallerTowerPrintsAsAShellBetweenTheTowersLayers) {
  PrintConfig c;
  c.paths.fill_density = 1.0;
  for (const TriangleMesh& m : {test::rib_beside_tower(), test::rib_against_tower()}) {
    const Outcome o = run(m, c);
    expect_good(o, 0);
    EXPECT_EQ(o.result.shell_layers, 2);
    EXPECT_LE(o.figures.deviation_p95, 0.005);
    EXPECT_GT(o.figures.within_share, 0.93);
    EXPECT_NEAR(o.figures.volume_ratio, 1.0, 0.03);
    // Layers reach the tower's top, and the print goes down again at least once: a core layer
    // after a higher piece of shell.
    double highest = 0;
    int downs = 0;
    for (std::size_t i = 0; i < o.result.layers.size(); ++i) {
      highest = std::max(highest, o.result.layers[i].max_z);
      downs += i > 0 && o.result.layers[i].z < o.result.layers[i - 1].z - 1e-6;
    }
    EXPECT_NEAR(highest, 14.0, 0.2);
    EXPECT_GT(downs, 0);
  }
}

// The rib over a void whose ceiling lies 0.25 mm under its top at x = 20: no layer of a
// shell rests on the core there. The shell leaves the void's footprint to the planar core and
// prints the rest (it was refused whole: within 0.03 mm on 31 % of the top).
TEST(NonplanarPrint, RibOverAVoidLeavesItsFootprintPlanar) {
  TriangleMesh m = test::rib();
  TriangleMesh hole = test::box({20, 3, 5}, {40, 9, 7.1});
  for (auto& f : hole.faces) std::swap(f[1], f[2]);
  test::append(m, hole);
  const Outcome o = run(m);
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_TRUE(o.result.nonplanar);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  EXPECT_GT(o.figures.within_share, 0.8);  // the planar footprint: about 12 % of the top
  bool said = false;
  for (const Notice& n : o.result.notices)
    said |= n.text.find("printed planar: an overhang") != std::string::npos;
  EXPECT_TRUE(said);
}

// A hollow part (#19: "part is not solid ... up to the patch" on mouse shells and hulls): no
// stack fits, and a shell rests on the wall under the top. With 1.5 mm walls the usual four
// layers fit over it; with 0.8 mm walls the ceiling lay within 0.5 mm under their bottom and
// the shell was refused (planar: within 0.03 mm on 27 % of the top). Now it takes two layers,
// the core's stairs standing on the ceiling beneath them. (Four asked for: the default is two.)
TEST(NonplanarPrint, HollowRoofPrintsAShellAsDeepAsItsWallAllows) {
  PrintConfig c;
  c.paths.fill_density = 1.0;
  c.shell_layers = 4;
  for (const auto& [wall, layers] : {std::pair{1.5, 4}, std::pair{0.8, 2}}) {
    SCOPED_TRACE(wall);
    const Outcome o = run(test::hollow_roof(wall), c);
    expect_good(o, 0);
    EXPECT_EQ(o.result.shell_layers, layers);
    EXPECT_GT(o.figures.within_share, 0.95);
    EXPECT_NEAR(o.figures.volume_ratio, 1.0, 0.04);
  }
}

// The CurviSlicer wing: its top runs from the bed at the nose to 17.5 mm; its windows' floors
// (3.12 and 3.55-3.58 mm, 29 % of the printable area) are planar core layer boundaries.
// PrusaSlicer's planar p95 on it is 0.089 mm; before the shell ours was the same.
TEST(NonplanarPrint, SharedWingPrintsAsAShell) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_wing.stl", {}, {});
  ASSERT_TRUE(m);
  const Outcome o = run(m->mesh);
  expect_good(o, 0);
  EXPECT_EQ(o.result.shell_layers, 2);
}

// The CurviSlicer airfoil rib: a 2.5-3.6 mm upper skin over truss holes, its trailing edge
// 0.27 mm thick on the bed. A shell over the skin leaves to the core only where a hole's
// ceiling or the edge's underside comes within N·t + 0.5 mm under the top (26 mm²); when each
// such face's whole footprint was left out, the shell lost 492 mm² and was refused (planar:
// 29 % of the curved top within 0.03 mm, as PrusaSlicer).
TEST(NonplanarPrint, SharedAirfoilRibPrintsAShellOverItsTrussHoles) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_airfoil.stl", {}, {});
  ASSERT_TRUE(m);
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(m->mesh, {}, cp);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_EQ(o.result.collisions, 0u);
  EXPECT_GT(o.figures.within_share, 0.8);
  EXPECT_LE(o.figures.steepest_deg, 30.5);
}

// The CurviSlicer car: its stacks follow 172 mm² of the curved top (the roof), while its
// 486 mm² body has none (hollow under the hood). A shell over all its curved patches (body,
// cabin, roof, wheel arches) prints instead. The
// mesh's overlapping shells put body triangles of different heights over one spot, and H rose
// 0.8 mm in 0.4 mm there: the core prints such spots whole (the shell was refused for an
// extrusion steeper than max_angle). Planar and with the stacks: 33 % within 0.03 mm.
TEST(NonplanarPrint, SharedCarPrintsAShellWhereItsStacksCoverLittle) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_car_med.stl", {}, {});
  ASSERT_TRUE(m);
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(m->mesh, {}, cp);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_TRUE(o.result.plan.stacks.empty());
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_EQ(o.result.collisions, 0u);
  // All nine curved patches in one shell (the body alone gave 0.57; planar gives about 0.3).
  EXPECT_GT(o.figures.within_share, 0.8);
  EXPECT_LE(o.figures.steepest_deg, 30.5);
  bool said = false;
  for (const Notice& n : o.result.notices)
    said |= n.text.find("patches 0, 1, 2") != std::string::npos &&
            n.text.find("where stacks would cover") != std::string::npos;
  EXPECT_TRUE(said);
}

// The Slic3r spiky block: its stacks cover 154 mm² of a 1342 mm² curved top, so a shell over
// all 20 tilted facets is tried first. It was refused ("an extrusion would hit earlier
// layers"): where the shell's print order g steps across several core layers at once, a piece
// of path kept the core layers in between and was printed too late, 0.105 mm under a shell
// point 0.45 mm away. Now it prints: 87 % of the curved top within 0.03 mm (the stacks: 22 %).
TEST(NonplanarPrint, SharedSpikyBlockPrintsAShellOverAllItsFacets) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_slic3r_nonplanar_spikey_top.stl", {}, {});
  ASSERT_TRUE(m);
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(m->mesh, {}, cp);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_GT(o.figures.within_share, 0.8);
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  bool all = false;
  for (const Notice& n : o.result.notices)
    all |= n.text.find(
               "patches 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, "
               "19: curved shell") != std::string::npos;
  EXPECT_TRUE(all);
}

// choose_shells' set as slice prints it: the first over the whole part, each further one framed
// over its own surroundings with a region, all on one core, no patch in two.
void expect_shells_apart(const std::vector<layers::ShellPlan>& shells) {
  EXPECT_FALSE(shells[0].framed);
  for (std::size_t i = 1; i < shells.size(); ++i) {
    EXPECT_TRUE(shells[i].framed);
    EXPECT_FALSE(shells[i].region.empty());
    EXPECT_EQ(shells[i].core, shells[0].core);
    for (std::size_t j = 0; j < i; ++j)
      for (int p : shells[i].patches)
        EXPECT_EQ(std::count(shells[j].patches.begin(), shells[j].patches.end(), p), 0);
  }
}

// The print of n shells: no collision, `share` of the curved top within 0.03 mm, the gate's
// thickness within the limits (check pairs a piece of shell with whatever was printed last
// below it, which between interleaved pieces can be another piece: 0.094 mm on the bunny),
// and a notice naming the shells.
// The extrusion runs (extruding moves between travels or retractions) shorter than `len` mm in
// XY, of the print's own lines.
std::size_t short_runs(const std::string& gcode, double len) {
  auto moves = read_gcode_moves(gcode);
  EXPECT_TRUE(moves);
  std::size_t n = 0;
  double run = 0;
  bool in_run = false;
  for (const PrintMove& m : *moves) {
    const double xy = (m.to - m.from).head<2>().norm();
    if (m.extruding && m.layer >= 0) {
      run += xy, in_run = true;
    } else if (xy > 0 || m.filament < 0) {
      n += in_run && run < len;
      run = 0, in_run = false;
    }
  }
  return n;
}

void expect_shells_printed(const Outcome& o, std::size_t n, double share) {
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_EQ(o.result.collisions, 0u);
  EXPECT_GT(o.figures.within_share, share);
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_GE(o.result.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.result.thickness_max, lp.max_layer_height + 1e-3);
  bool named = false;
  for (const Notice& note : o.result.notices)
    named |= note.kind == Notice::Kind::shell &&
             note.text.find(std::to_string(n) + " curved shells") != std::string::npos;
  EXPECT_TRUE(named);
}

// The bunny's curved top lies at many heights: its back (112–129 mm), head (151–167 mm),
// tail and a cheek. One shell over the back alone followed 54 % of it within 0.03 mm; the part
// stands above that shell (the head), so each further group of patches gets its own shell,
// planned over its surroundings only. 82 % within 0.03 mm, 0 collisions. (One shell could
// follow it all, banded over 52 % of it: 82.9 % within 0.03 mm, but the slice took 5.5 s
// against 2.9, and the shells apart follow 86 % of its curved area: they are chosen.)
TEST(NonplanarPrint, SharedBunnyPrintsAShellPerCurvedRegion) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_stanford_bunny_closed_compas.stl", {}, {});
  ASSERT_TRUE(m);
  const PrintConfig c;
  const TriangleMesh mesh = test::placed(m->mesh, c);
  const Analysis a = *analyze(mesh, {}, {});
  const std::vector<layers::ShellPlan> shells = layers::choose_shells(mesh, a, make_job(c).layers);
  ASSERT_GE(shells.size(), 3u);
  expect_shells_apart(shells);
  CheckParams cp;
  cp.min_angle_deg = 2;
  expect_shells_printed(run(m->mesh, c, cp), shells.size(), 0.8);
}

// The XY length of the file's travels, mm.
double travel_length(const std::string& gcode) {
  auto moves = read_gcode_moves(gcode);
  EXPECT_TRUE(moves);
  double l = 0;
  for (const PrintMove& m : *moves)
    if (!m.extruding && m.layer >= 0) l += (m.to - m.from).head<2>().norm();
  return l;
}

// The bunny's path on a small part (it runs under the sanitizers, the bunny does not): two
// reliefs too tall for stacks, apart, each under its own shell on one core. 90.6 % of the
// curved top within 0.03 mm, 0 collisions.
TEST(NonplanarPrint, TwoReliefsApartGetAShellEach) {
  const PrintConfig c;  // one shell over both would be banded over 57 % of it
  const TriangleMesh mesh = test::placed(test::two_reliefs(), c);
  const Analysis a = *analyze(mesh, {}, {});
  const std::vector<layers::ShellPlan> shells = layers::choose_shells(mesh, a, make_job(c).layers);
  ASSERT_EQ(shells.size(), 2u);
  expect_shells_apart(shells);
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(test::two_reliefs(), c, cp);
  expect_shells_printed(o, 2, 0.85);
  // No blobs (NonplanarPrint.ShellPrintsNoBlobs): 511 runs under 0.1 mm once, 2 left (tiny
  // loops of the core's own, cut back under a shell).
  EXPECT_LE(short_runs(o.gcode, 0.1), 5u);
  // Pieces of a layer beyond the head's reach of each other print group by group, not across
  // the part in turn (the top skins by height over each relief, the pieces of a layer between
  // two core layers): 40.9 m of travel, 78.7 m before.
  EXPECT_LT(travel_length(o.gcode), 50'000);
}

// The shapes #19 asks the figures for (support/solids.hpp): a mouse's 1.2 mm shell, a top over a
// pocket, a CAD block's fillets, a terrain tile, and a top partly under another (the shelf over
// the block, which stands above that part of it). Their curved top within 0.03 mm: 100 %, and
// 89.3 % where the shelf leaves the block's top under it planar; planar slicing 27-38 %.
struct IssueShape {
  const char* name;
  TriangleMesh (*make)();
  double within;  ///< the least share of the curved top within 0.03 mm
};

class IssueShapes : public ::testing::TestWithParam<IssueShape> {};

TEST_P(IssueShapes, PrintTheirCurvedTopWithinLimits) {
  const PrintConfig c;
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(GetParam().make(), c, cp);
  EXPECT_GE(o.result.printed_curved, 1);
  EXPECT_EQ(o.result.collisions, 0u);
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_GE(o.figures.within_share, GetParam().within);
  const LayerParams lp = make_job(c).layers;
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  EXPECT_LE(o.figures.steepest_deg, lp.max_angle_deg + 0.5);
  // The same part planar: the figure tells the two apart.
  const TriangleMesh mesh = test::placed(GetParam().make(), c);
  SliceJob job = make_job(c);
  job.planar_only = true;
  auto planar = slice_model(mesh, job, {});
  ASSERT_TRUE(planar) << planar.error().message;
  auto moves = read_gcode_moves(planar->gcode);
  ASSERT_TRUE(moves) << moves.error().message;
  auto f = check_print(*moves, &mesh, cp, {});
  ASSERT_TRUE(f);
  EXPECT_LT(f->within_share, 0.5);
}

INSTANTIATE_TEST_SUITE_P(
    NonplanarPrint, IssueShapes,
    ::testing::Values(IssueShape{"mouse_shell", test::mouse_shell, 0.99},
                      IssueShape{"top_over_pocket", test::top_over_pocket, 0.99},
                      IssueShape{"filleted_block", test::filleted_block, 0.99},
                      IssueShape{"terrain_tile", test::terrain_tile, 0.99},
                      IssueShape{"tops_one_over_another", test::tops_one_over_another, 0.85}),
    [](const ::testing::TestParamInfo<IssueShape>& i) { return std::string(i.param.name); });

// A shell's curved layers are a setting (#19: "k is configurable"): with shell_layers = 2 the
// rib's shell has 2, its top as close (100 % within 0.03 mm), the core's solid layers under it,
// and the print 30m50s against 33m19s with the automatic 4 (the car 45m09s against 57m36s).
// `shell_layers` is ours: not passed on to another slicer.
TEST(NonplanarPrint, ShellLayersIsASetting) {
  EXPECT_TRUE(is_nonplanar_key("shell_layers"));
  for (const int k : {2, 1}) {
    PrintConfig c;
    ASSERT_TRUE(set_config_value(c, "shell_layers", std::to_string(k)));
    ASSERT_TRUE(validate_config(c));
    CheckParams cp;
    cp.min_angle_deg = 2;
    const Outcome o = run(test::rib(), c, cp);
    EXPECT_EQ(o.result.shell_layers, k);
    EXPECT_NE(o.gcode.find("a shell of " + std::to_string(k) + " curved layer"), std::string::npos);
    EXPECT_EQ(o.figures.collisions, 0u);
    EXPECT_GE(o.figures.within_share, 0.99);
    const LayerParams lp = make_job(c).layers;
    EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
    EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  }
}

// The CurviSlicer ankle base's outer ring lies under its inner ring's rim all round: a shell
// over both is banded over 69 % of them. At shell_max_banded 0.5 it is refused (the inner ring
// alone gets a shell: 72 % of the curved top within 0.03 mm); by default (1) it prints, its top
// lines up and down the slope: 80.7 % within, 0 collisions, 50m25s against 47m10s.
TEST(NonplanarPrint, BandedShellIsASetting) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_anklebase_small.stl", {}, {});
  ASSERT_TRUE(m);
  CheckParams cp;
  cp.min_angle_deg = 2;
  PrintConfig c;
  const Outcome banded = run(m->mesh, c, cp);
  ASSERT_TRUE(set_config_value(c, "shell_max_banded", "0.5"));
  const Outcome held = run(m->mesh, c, cp);
  EXPECT_EQ(banded.result.shell_layers, 2);
  EXPECT_EQ(banded.figures.collisions, 0u);
  EXPECT_GT(banded.figures.within_share, held.figures.within_share + 0.05);
  EXPECT_GE(banded.figures.within_share, 0.80);
}

// Stacks and a shell in one part (#19): the domed tower gets a stack, the rib beside it (no
// stack fits: its layer count would change 40-fold) a shell, over one core whose layers bend
// under the dome. The stack is planned on the core's layers (h_c = 0.18 mm after the first),
// so its plane lies on a core boundary. 99.9 % of the curved top within 0.03 mm, against
// 70.7 % with the stack alone (the rib planar), 0 collisions.
TEST(NonplanarPrint, StackAndShellInOnePart) {
  PrintConfig c;
  CheckParams cp;
  cp.min_angle_deg = 2;
  const Outcome o = run(test::rib_and_domed_tower(), c, cp);
  ASSERT_EQ(o.result.plan.stacks.size(), 1u);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_EQ(o.result.printed_curved, 2);
  EXPECT_EQ(o.figures.collisions, 0u);
  EXPECT_EQ(o.result.collisions, 0u);
  EXPECT_GT(o.figures.within_share, 0.95);
  EXPECT_LE(o.figures.deviation_p95, 0.01);
  const LayerParams lp = make_job(c).layers;
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  EXPECT_LE(o.figures.steepest_deg, make_job(c).layers.max_angle_deg + 0.5);
  const LayerStack& st = o.result.plan.stacks.front();
  const double h_c = 0.18, steps = (st.c - h_c) / h_c;  // the core's first layer is h_c too
  EXPECT_NEAR(steps, std::round(steps), 1e-6) << st.c;
  EXPECT_NE(o.gcode.find("; patch 0: " + std::to_string(st.layers) + " curved layers"),
            std::string::npos);
  EXPECT_NE(o.gcode.find("a shell of 2 curved layers"), std::string::npos);
  // Without shells the rib prints planar.
  const TriangleMesh mesh = test::placed(test::rib_and_domed_tower(), c);
  SliceJob job = make_job(c);
  job.shells = false;
  auto alone = slice_model(mesh, job, {});
  ASSERT_TRUE(alone) << alone.error().message;
  EXPECT_EQ(alone->shell_layers, 0);
  auto moves = read_gcode_moves(alone->gcode);
  ASSERT_TRUE(moves) << moves.error().message;
  auto f = check_print(*moves, &mesh, cp, {});
  ASSERT_TRUE(f);
  EXPECT_LT(f->within_share, 0.8);
}

// A low domed block 2 mm before the rib's nose: the stack's blend reaches over the nose,
// where the shell cuts the core back from the bed up, so the two do not print together (the
// stack prints, the rib planar); whatever prints keeps every limit.
TEST(NonplanarPrint, StackWhoseBlendMeetsTheShellsCutPrintsAlone) {
  TriangleMesh m = test::height_field_solid(
      [](double x, double) { return 0.3 + 12 * std::sin(M_PI * x / 100); }, 0, 60, 0, 12, 120, 12);
  test::append(m, test::height_field_solid(
                      [](double x, double y) {
                        return 12 + 2.0 * std::cos(0.1 * (x - 77)) * std::cos(0.1 * (y - 6));
                      },
                      62, 92, -9, 21, 60, 60));
  const Outcome o = run(m);
  EXPECT_EQ(o.figures.collisions, 0u);
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_LE(o.figures.thickness_max, lp.max_layer_height + 1e-3);
  EXPECT_LE(o.figures.steepest_deg, lp.max_angle_deg + 0.5);
  EXPECT_EQ(o.result.plan.stacks.size(), 1u);
  EXPECT_EQ(o.result.shell_layers, 0);
  bool said = false;
  for (const Notice& n : o.result.notices)
    said |= n.kind == Notice::Kind::shell_refused &&
            n.text.find(
                "not printed as a shell beside the stacks: it would cut the core back "
                "where a stack bends its layers") != std::string::npos;
  EXPECT_TRUE(said);
}

// A shell over a rib whose nose meets the bed beside a low block: the shell's pieces cut
// between the core's layers and the slivers of its region left beads of a few microns, each
// between a retraction and its give-back (74 in this file, 511 in the two reliefs', 1015 in
// the bunny's; a planar print has none), and one of them lay 0.005 mm over the first layer.
// Beads shorter than 0.1 mm are no longer printed.
TEST(NonplanarPrint, ShellPrintsNoBlobs) {
  TriangleMesh m = test::height_field_solid(
      [](double x, double) { return 0.3 + 12 * std::sin(M_PI * x / 100); }, 0, 60, 0, 12, 120, 12);
  test::append(m, test::height_field_solid(
                      [](double x, double y) {
                        return 3 + 1.0 * std::cos(0.1 * (x + 17)) * std::cos(0.1 * (y - 6));
                      },
                      -32, -2, -9, 21, 60, 60));
  const Outcome o = run(m);
  EXPECT_GT(o.result.shell_layers, 0);
  EXPECT_EQ(o.figures.collisions, 0u);
  const LayerParams lp = make_job(PrintConfig{}).layers;
  EXPECT_GE(o.figures.thickness_min, lp.min_layer_height - 1e-3);
  EXPECT_EQ(short_runs(o.gcode, 0.1), 0u);
}

// At 0.15 mm layers a shell of the profile's layer height put the nozzle tip's flat into
// the layer below uphill on the wing's 27–29° facets (the collision test's depth is h/2), and
// the wing went planar, as with the MK3S 0.15 SPEED preset. Its layers are now as thick as
// the tip needs there: 0.21 mm (its steepest facet is 29°).
TEST(NonplanarPrint, SharedWingShellAtThinLayersClearsTheTip) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_wing.stl", {}, {});
  ASSERT_TRUE(m);
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "layer_height", "0.15"));
  const TriangleMesh mesh = test::placed(m->mesh, c);
  const SliceJob job = make_job(c);
  auto r = slice_model(mesh, job, {});
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_GT(r->shell_layers, 0);
  auto moves = read_gcode_moves(r->gcode);
  ASSERT_TRUE(moves) << moves.error().message;
  auto f = check_print(*moves, &mesh, check_params(c, 30), {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->collisions, 0u);
  EXPECT_LE(f->deviation_p95, 0.02);
  EXPECT_GE(f->thickness_min, job.layers.min_layer_height - 1e-3);
  EXPECT_LE(f->thickness_max, job.layers.max_layer_height + 1e-3);
  // The shell's layers are thicker than the core's 0.15 mm.
  EXPECT_GT(r->thickness_max, 0.2);
}

// The OpenSCAD heightmap: patch 0's stack meets every limit on its own grid (29.0°) but its
// final paths hold an extrusion steeper than max_angle, so the gate refuses it and a shell
// over both curved patches prints; the notice says why there is no stack, not "none fits".
TEST(NonplanarPrint, SharedHeightmapSaysItsStackBrokeALimitWhenAShellPrints) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_openscad_example010_heightmap.stl", {}, {});
  ASSERT_TRUE(m);
  const Outcome o = run(m->mesh);
  EXPECT_EQ(o.result.shell_layers, 2);
  EXPECT_EQ(o.figures.collisions, 0u);
  bool said = false;
  for (const Notice& n : o.result.notices)
    said |= n.text.find(
                "curved shell over a planar core (its stacks broke a limit in their "
                "final paths)") != std::string::npos;
  EXPECT_TRUE(said);
}

TEST(NonplanarPrint, FlatTopsSlicePlanarWithANotice) {
  const Outcome o = run(test::box({0, 0, 0}, {20, 20, 10}));
  EXPECT_FALSE(o.result.nonplanar);
  ASSERT_FALSE(o.result.notices.empty());
  EXPECT_NE(o.result.notices.back().text.find("slicing planar"), std::string::npos);
  EXPECT_NEAR(o.figures.steepest_deg, 0.0, 1e-9);
}

TEST(GcodeReader, RefusesArcsAndUnknownCommandsNamingTheLine) {
  auto arc = read_gcode_moves("G90\nG1 X1 Y1 E1\nG2 X5 Y5 I1 J1 E2\n");
  ASSERT_FALSE(arc);
  EXPECT_NE(arc.error().message.find("line 3: arc"), std::string::npos) << arc.error().message;
  auto junk = read_gcode_moves("G1 X1\nhello\n");
  ASSERT_FALSE(junk);
  EXPECT_NE(junk.error().message.find("line 2"), std::string::npos);
  auto ok = read_gcode_moves("M83\nG1 X1 Y0 E0.5 ; note\nG92 E0\nT0\nM104 S200\n");
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_EQ(ok->size(), 1u);
  EXPECT_TRUE((*ok)[0].extruding);
}

}  // namespace
}  // namespace nonplanar
