// The safety gate (pipeline/gate.hpp) on a program without bands, where it looks for
// collisions only at the heights printed out of order (gate_zones.hpp's out_of_order).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "nonplanar/check.hpp"
#include "pipeline/gate.hpp"
#include "pipeline/gate_zones.hpp"

namespace nonplanar {
namespace {

// A bead of 0.2 mm layers along the points.
ExtrusionPath path(std::vector<Vec3> points) {
  ExtrusionPath p;
  p.points = std::move(points);
  p.height.assign(p.points.size(), 0.2);
  return p;
}

LayerToolpaths layer(double z, std::vector<ExtrusionPath> paths, bool curved = false) {
  LayerToolpaths L;
  L.z = L.max_z = z;
  L.paths = std::move(paths);
  L.nonplanar = curved;
  for (const ExtrusionPath& p : L.paths)
    for (const Vec3& v : p.points) L.max_z = std::max(L.max_z, v.z());
  return L;
}

// Two planar layers, then a ramp (a shell piece) up to 4.6 mm, then a planar layer at 0.6 mm
// that runs under the ramp's high end (printed after it, as a core layer after a shell piece
// slotted early would be), then planar layers above everything.
std::vector<LayerToolpaths> ramp_then_core(double core_x) {
  std::vector<LayerToolpaths> L;
  L.push_back(layer(0.2, {path({{100, 100, 0.2}, {120, 100, 0.2}})}));
  L.push_back(layer(0.4, {path({{100, 100, 0.4}, {120, 100, 0.4}})}));
  // 4.2 mm over 10 mm: 22.8°, within max_angle.
  L.push_back(layer(4.6, {path({{100, 105, 0.4}, {110, 105, 4.6}, {120, 105, 4.6}})}, true));
  L.push_back(layer(0.6, {path({{core_x, 95, 0.6}, {core_x, 115, 0.6}})}));
  for (int k = 0; k < 30; ++k) {
    const double z = 4.8 + 0.2 * k;
    L.push_back(layer(z, {path({{100, 100, z}, {120, 100, z}})}));
  }
  return L;
}

TEST(GateZones, OutOfOrderSpansThePointsPrintedBelowEarlierOnes) {
  // In order: nothing can meet earlier material.
  std::vector<LayerToolpaths> planar;
  for (int k = 0; k < 5; ++k)
    planar.push_back(layer(0.2 * (k + 1), {path({{0, 0, 0.2 * (k + 1)}, {10, 0, 0.2 * (k + 1)}})}));
  const OutOfOrder none = out_of_order(planar);
  EXPECT_TRUE(none.spans.empty());
  // The core layer at 0.6 mm comes after the ramp's 4.6 mm: it alone is out of order, and the
  // layers above 4.6 mm are not.
  const OutOfOrder late = out_of_order(ramp_then_core(115));
  ASSERT_EQ(late.spans.size(), 1u);
  EXPECT_DOUBLE_EQ(late.spans[0].lo, 0.6);
  EXPECT_DOUBLE_EQ(late.spans[0].hi, 0.6);
  EXPECT_EQ(late.spans[0].last_layer, 3);
  EXPECT_TRUE(late.looked_at(Vec3(0, 0, 1.5)));
  EXPECT_FALSE(late.looked_at(Vec3(0, 0, 1.7)));
  EXPECT_TRUE(late.may_matter(4.6, 1));
  EXPECT_FALSE(late.may_matter(4.6, 4));   // printed after the last point out of order
  EXPECT_FALSE(late.may_matter(-0.5, 1));  // under every such point
}

// Two shells far apart in height, each printed between the core's layers: two spans, and
// what is printed between them matters to neither.
TEST(GateZones, OutOfOrderKeepsShellsAtDifferentHeightsApart) {
  std::vector<LayerToolpaths> L;
  auto flat = [&](double z) { L.push_back(layer(z, {path({{0, 0, z}, {10, 0, z}})})); };
  for (int k = 1; k <= 10; ++k) flat(0.2 * k);    // layers 0-9, up to 2 mm
  flat(2.3), flat(2.1);                           // 10, 11: 2.1 after 2.3
  for (int k = 11; k <= 100; ++k) flat(0.2 * k);  // 12-101, up to 20 mm
  flat(20.3), flat(20.15);                        // 102, 103: 20.15 after 20.3
  const OutOfOrder o = out_of_order(L);
  ASSERT_EQ(o.spans.size(), 2u);
  EXPECT_DOUBLE_EQ(o.spans[0].lo, 2.1);
  EXPECT_EQ(o.spans[0].last_layer, 12);  // the core's 2.2 mm after the 2.3 mm piece
  EXPECT_DOUBLE_EQ(o.spans[1].lo, 20.15);
  EXPECT_EQ(o.spans[1].last_layer, 103);
  EXPECT_FALSE(o.looked_at(Vec3(0, 0, 10)));
  EXPECT_FALSE(o.may_matter(10, 50));  // above the first span, but printed after it
  EXPECT_TRUE(o.may_matter(19.5, 101));
}

// The gate finds the core layer that runs into the ramp printed before it, though it searches
// only layers 0-3 above 0.6 - 1 mm; a core layer well clear of the ramp passes.
TEST(Gate, FindsACollisionWithAShellPiecePrintedEarlierWithoutBands) {
  const SliceJob job = make_job(PrintConfig{});
  auto run = [&](double core_x, std::string* what) {
    SliceResult r;
    r.layers = ramp_then_core(core_x);
    r.nonplanar = true;
    auto ok = gate(r, job, nullptr,
                   [&](const Vec3&, const char* w) {
                     *what = w;
                     return false;
                   },
                   {});
    EXPECT_TRUE(ok) << ok.error().message;
    EXPECT_TRUE(r.stats_in_gcode);
    EXPECT_GT(r.stats.filament_mm, 0);
    return ok && *ok;
  };
  std::string what;
  EXPECT_FALSE(run(115, &what));  // under the ramp's top: material 4 mm over the nozzle
  EXPECT_EQ(what, "the nozzle would hit earlier layers");
  what.clear();
  EXPECT_TRUE(run(160, &what)) << what;  // 40 mm away, beyond the heater block
}

// The gate's figures do not depend on where its passes read the moves: all held (a small
// program), the few near the out-of-order heights held while the rest of a larger one is not,
// or, past the most it holds, the text each time.
TEST(Gate, SameFiguresWhereverItReadsTheMoves) {
  for (const double core_x : {115.0, 160.0}) {
    std::vector<std::string> verdicts;
    std::vector<double> thickness;
    for (const std::size_t most : {std::size_t(250000), std::size_t(60), std::size_t(3)}) {
      SliceJob job = make_job(PrintConfig{});
      job.gate.held_moves = most;
      SliceResult r;
      r.layers = ramp_then_core(core_x);
      r.nonplanar = true;
      std::string what = "passed";
      auto ok =
          gate(r, job, nullptr,
               [&](const Vec3& p, const char* w) {
                 char buf[160];
                 std::snprintf(buf, sizeof buf, "%s at %.3f %.3f %.3f", w, p.x(), p.y(), p.z());
                 what = buf;
                 return false;
               },
               {});
      ASSERT_TRUE(ok) << ok.error().message;
      verdicts.push_back(what);
      thickness.push_back(r.thickness_min), thickness.push_back(r.thickness_max);
      if (most == 60) {  // more lines than that, fewer of them out of order
        EXPECT_GT(count_gcode_lines(r.gcode).g_lines, most);
      }
    }
    EXPECT_NE(verdicts[0].find(core_x < 150 ? "hit earlier layers" : "passed"), std::string::npos)
        << verdicts[0];
    for (std::size_t k = 1; k < verdicts.size(); ++k) EXPECT_EQ(verdicts[k], verdicts[0]) << k;
    for (std::size_t k = 2; k < thickness.size(); ++k)
      EXPECT_EQ(thickness[k], thickness[k % 2]) << k;
  }
}

// A program as another slicer's route hands it over: the slope limit is judged on the lines
// written, the print's own only. The user's start block and the skirt climb steeply and do not
// count; a perimeter that climbs 2 mm over 4 mm (26.57°) is within 30°, one that climbs 2 mm
// over 1.5 mm (53.13°) is not, and the breach is reported at the line's end.
TEST(Gate, JudgesSlopesOnTheProgramWritten) {
  const SliceJob job = make_job(PrintConfig{});
  auto run = [&](double run_x, Vec3* where, SliceResult* r) {
    r->gcode =
        "G90\nM82\nG92 E0\n;TYPE:Custom\nG1 X10 Y10 Z0.3 F3000\nG1 X12 Y10 Z3 E1\n"
        ";LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\n;TYPE:Skirt/Brim\nG1 X30 Y10 Z0.2\n"
        "G1 X32 Y10 Z2 E2\n;TYPE:External perimeter\nG1 X40 Y10 Z0.2\nG1 X" +
        std::to_string(40 + run_x) + " Y10 Z2.2 E3\n";
    auto ok = gate(*r, job, nullptr,
                   [&](const Vec3& p, const char* w) {
                     EXPECT_STREQ(w, "an extrusion is steeper than max_angle");
                     *where = p;
                     return false;
                   },
                   {});
    EXPECT_TRUE(ok) << ok.error().message;
    return ok && *ok;
  };
  Vec3 where(0, 0, 0);
  SliceResult gentle;
  EXPECT_TRUE(run(4, &where, &gentle));
  EXPECT_NEAR(gentle.steepest_deg, std::atan2(2.0, 4.0) * 180 / M_PI, 1e-9);
  SliceResult steep;
  EXPECT_FALSE(run(1.5, &where, &steep));
  EXPECT_NEAR((where - Vec3(41.5, 10, 2.2)).norm(), 0, 1e-9);
}

// Thickness where a curved layer's line crosses the one under it, judged on the program: a
// line over layer 0 at (110, 100) 0.09 mm up is thinner than h_min (0.1, slack 0.001); 0.13 mm
// up passes, and the gate's figure is what check measures on the same text.
TEST(Gate, JudgesThicknessWhereALayerCrossesTheOneUnderIt) {
  const SliceJob job = make_job(PrintConfig{});
  auto text = [](double z) {
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "G90\nM82\nG92 E0\n;LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\n;TYPE:Solid infill\n"
                  "G1 X100 Y100 Z0.2\nG1 X120 Y100 E1\n;LAYER_CHANGE\n;Z:0.4\n;HEIGHT:0.2\n"
                  "G1 X110 Y95 Z%.3f\nG1 X110 Y105 Z%.3f E2\n",
                  z - 0.01, z + 0.01);
    return std::string(buf);
  };
  auto run = [&](double z, Vec3* where, SliceResult* r) {
    r->gcode = text(z);
    auto ok = gate(*r, job, nullptr,
                   [&](const Vec3& p, const char* w) {
                     EXPECT_STREQ(w, "a layer crosses the one under it thinner than h_min");
                     *where = p;
                     return false;
                   },
                   {});
    EXPECT_TRUE(ok) << ok.error().message;
    return ok && *ok;
  };
  Vec3 where(0, 0, 0);
  SliceResult thin;
  EXPECT_FALSE(run(0.29, &where, &thin));
  EXPECT_NEAR((where - Vec3(110, 100, 0.29)).norm(), 0, 1e-9);
  SliceResult fine;
  EXPECT_TRUE(run(0.33, &where, &fine));
  EXPECT_NEAR(fine.thickness_min, 0.13, 1e-9);
  auto moves = read_gcode_moves(fine.gcode);
  ASSERT_TRUE(moves);
  auto f = check_print(*moves, nullptr, job.check, {});
  ASSERT_TRUE(f);
  EXPECT_EQ(f->thickness_min, fine.thickness_min);
  EXPECT_EQ(f->thickness_max, fine.thickness_max);
}

}  // namespace
}  // namespace nonplanar
