// The plan prepare writes and post-process reads (print_plan.hpp, field_io.hpp), and
// post_process_gcode on G-code of the prepared part. The "slicer" here is our own planar
// engine with a PrusaSlicer settings block appended, so these run without PrusaSlicer
// (tests/cli/test_post_process.cpp runs the real one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "layers/shell_plan.hpp"
#include "nonplanar/check.hpp"
#include "nonplanar/field_io.hpp"
#include "nonplanar/print_plan.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

struct Prepared {
  TriangleMesh mesh;  // placed
  PreparedPart part;
};

const Prepared& dome() {
  static const Prepared p = [] {
    Prepared d;
    d.mesh = test::placed(test::dome_cut_by_box(), PrintConfig{});
    auto part = prepare_part(d.mesh, make_job(PrintConfig{}), {});
    EXPECT_TRUE(part) << part.error().message;
    d.part = std::move(*part);
    return d;
  }();
  return p;
}

// Our planar engine's G-code of `mesh` with the settings `c` (no settings block).
std::string planar_gcode(const TriangleMesh& mesh, const PrintConfig& c = {}) {
  SliceJob job = make_job(c);
  job.planar_only = true;
  auto r = slice_model(mesh, job, {});
  EXPECT_TRUE(r) << r.error().message;
  return r ? r->gcode : std::string();
}

// A slicer's planar G-code of `mesh` (ours), ending in the settings block PrusaSlicer writes:
// c's layer heights, then `block_extra`.
std::string sliced(const TriangleMesh& mesh, const std::string& block_extra = "",
                   const PrintConfig& c = {}) {
  char heights[120];
  std::snprintf(heights, sizeof heights, "; layer_height = %g\n; first_layer_height = %g\n",
                c.slice.layer_height, c.slice.first_layer_height);
  return planar_gcode(mesh, c) + "; prusaslicer_config = begin\n" + heights + block_extra +
         "; prusaslicer_config = end\n";
}

TriangleMesh moved(TriangleMesh m, const Vec3& by) {
  for (Vec3& v : m.vertices) v += by;
  return m;
}

TEST(PrintPlan, FieldReadsBackBitForBitAndShifted) {
  const Prepared& d = dome();
  ASSERT_EQ(d.part.stacks, 1u);
  const LayerField& F = *d.part.field;
  auto back = parse_layer_field_json(d.part.plan.field);
  ASSERT_TRUE(back) << back.error().message;
  auto shifted = parse_layer_field_json(d.part.plan.field, {7.5, -3.25});
  ASSERT_TRUE(shifted);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(80, 120), z(0, 12);
  double worst_shift = 0, most_bent = 0;
  for (int k = 0; k < 2000; ++k) {
    const double x = xy(rng), y = xy(rng), h = z(rng);
    const double t = F.T(x, y, h);
    ASSERT_EQ((*back)->T(x, y, h), t);  // the very same doubles
    ASSERT_EQ((*back)->z_at(x, y, t), F.z_at(x, y, t));
    worst_shift = std::max(worst_shift, std::abs((*shifted)->T(x + 7.5, y - 3.25, h) - t));
    most_bent = std::max(most_bent, std::abs(F.zeta(t) - h));
  }
  EXPECT_LT(worst_shift, 1e-9);
  EXPECT_GT(most_bent, 0.5);  // the field does bend the layers there (a planar one would pass)
}

TEST(PrintPlan, PlanReadsBack) {
  PrintPlan p = dome().part.plan;
  p.object = "dome", p.model = "dome.stl";
  p.toolhead.shape = {{2.0, {{{-3, -3}, {3, -3}, {3, 3}, {-3, 3}}}}};
  p.toolhead.shape_name = "test head";
  auto back = parse_plan_json(plan_json(p));
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->object, "dome");
  EXPECT_EQ(back->box.min, p.box.min);
  EXPECT_EQ(back->box.max, p.box.max);
  EXPECT_EQ(back->layer_height, p.layer_height);
  EXPECT_EQ(back->first_layer_height, p.first_layer_height);
  EXPECT_EQ(back->max_layer_height, p.max_layer_height);
  EXPECT_EQ(back->max_angle_deg, p.max_angle_deg);
  EXPECT_EQ(back->header, p.header);
  ASSERT_EQ(back->toolhead.shape.size(), 1u);
  EXPECT_EQ(back->toolhead.shape[0].polygons[0][2], Vec2(3, 3));
  EXPECT_EQ(back->toolhead.describe(), p.toolhead.describe());
}

TEST(PrintPlan, BadPlansAreRefusedNotTrusted) {
  const std::string good = plan_json(dome().part.plan);
  EXPECT_EQ(parse_plan_json("{}").error().status, Status::parse_error);
  std::string v2 = good;
  v2.replace(v2.find("\"version\": 1"), 12, "\"version\": 2");
  EXPECT_EQ(parse_plan_json(v2).error().status, Status::unsupported);
  // Cut anywhere: an error, never a crash or a plan.
  for (std::size_t cut : {std::size_t(10), good.size() / 3, good.size() / 2, good.size() - 5})
    EXPECT_FALSE(parse_plan_json(good.substr(0, cut))) << cut;
  // Sizes that disagree, values out of range.
  auto field_err = [&](const std::string& from, const std::string& to) {
    std::string f = dome().part.plan.field;
    const auto at = f.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    f.replace(at, from.size(), to);
    auto r = parse_layer_field_json(f);
    return r ? std::string() : r.error().message;
  };
  EXPECT_NE(field_err("\"nx\":", "\"nx\":1").find("must hold"), std::string::npos);
  EXPECT_NE(field_err("\"N\":", "\"N\":-").find("N"), std::string::npos);
  EXPECT_NE(field_err("\"cell\":", "\"cell\":-").find("cell"), std::string::npos);
  EXPECT_NE(field_err("\"layer_height\":", "\"layer_height\":1e9,\"x\":").find("layer heights"),
            std::string::npos);
}

// Arrays of doubles are written as base64 of their bytes; plain JSON arrays read the same.
TEST(PrintPlan, Base64AndPlainArraysReadAlike) {
  const std::string dir = NONPLANAR_TEST_DATA;
  auto a = parse_plan_json(test::read_bytes(dir + "/plan_small.json"));
  auto b = parse_plan_json(test::read_bytes(dir + "/plan_small_b64.json"));
  ASSERT_TRUE(a) << a.error().message;
  ASSERT_TRUE(b) << b.error().message;
  auto fa = parse_layer_field_json(a->field), fb = parse_layer_field_json(b->field);
  ASSERT_TRUE(fa) << fa.error().message;
  ASSERT_TRUE(fb) << fb.error().message;
  double bent = 0;
  for (double x = 104; x <= 116; x += 0.7)
    for (double z = 0.5; z < 6; z += 0.37) {
      ASSERT_EQ((*fa)->T(x, x - 1, z), (*fb)->T(x, x - 1, z));
      bent = std::max(bent, std::abs((*fa)->zeta((*fa)->T(x, x - 1, z)) - z));
    }
  EXPECT_GT(bent, 0.05);
}

TEST(PostProcess, MapsTheSlicersGcodeAsTheEngineRouteDoes) {
  const Prepared& d = dome();
  auto out = post_process_gcode(sliced(d.part.normalized), d.part.plan, {});
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_LT(out->moved.norm(), 1e-3);
  EXPECT_GE(out->thickness_min, d.part.plan.min_layer_height - 1e-3);
  EXPECT_LE(out->thickness_max, d.part.plan.max_layer_height + 1e-3);
  EXPECT_GT(out->steepest_deg, 10);  // curved
  EXPECT_EQ(out->gcode.rfind(kPostProcessedMark, 0), 0u);
  auto moves = read_gcode_moves(out->gcode);
  ASSERT_TRUE(moves);
  auto f = check_print(*moves, &d.mesh, check_params(PrintConfig{}, 30), {});
  ASSERT_TRUE(f);
  EXPECT_LE(f->deviation_p95, 0.02);
  EXPECT_EQ(f->collisions, 0u);
  // Twice would lift it twice.
  auto again = post_process_gcode(out->gcode, d.part.plan, {});
  ASSERT_FALSE(again);
  EXPECT_NE(again.error().message.find("already post-processed"), std::string::npos);
  // Also under the time estimate's first lines (a profile with remaining_times, the MK3S's).
  auto timed = post_process_gcode("M73 P0 R86\nM73 Q0 S86\n" + out->gcode, d.part.plan, {});
  ASSERT_FALSE(timed);
  EXPECT_NE(timed.error().message.find("already post-processed"), std::string::npos);
}

TEST(PostProcess, APartMovedOnThePlateIsFollowed) {
  const Prepared& d = dome();
  const Vec3 by(17.5, -9.25, 0);
  auto out = post_process_gcode(sliced(moved(d.part.normalized, by)), d.part.plan, {});
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_NEAR(out->moved.x(), by.x(), 0.02);
  EXPECT_NEAR(out->moved.y(), by.y(), 0.02);
  auto moves = read_gcode_moves(out->gcode);
  ASSERT_TRUE(moves);
  const TriangleMesh there = moved(d.mesh, by);
  // check places the mesh at the bed's centre; give it the moved part's own placement.
  CheckParams cp = check_params(PrintConfig{}, 30);
  auto f = check_print(*moves, &there, cp, {});
  ASSERT_TRUE(f);
  EXPECT_LE(f->deviation_p95, 0.02);
  EXPECT_EQ(f->collisions, 0u);
}

TEST(PostProcess, WhatThePlanNeedsIsRefusedByName) {
  const Prepared& d = dome();
  auto refused = [&](const std::string& gcode) {
    auto r = post_process_gcode(gcode, d.part.plan, {});
    EXPECT_FALSE(r);
    return r ? std::string() : r.error().message;
  };
  // Scaled (or rotated: its box changes too).
  TriangleMesh big = d.part.normalized;
  const BoundingBox b = bounding_box(big);
  for (Vec3& v : big.vertices) v.head<2>() = b.min.head<2>() + 1.15 * (v - b.min).head<2>();
  EXPECT_NE(refused(sliced(big)).find("scaled or rotated"), std::string::npos);
  // Another first layer; another layer height (the object's setting dropped, or variable
  // layer height on).
  PrintConfig thick, thin;
  thick.slice.first_layer_height = 0.3;
  thin.slice.layer_height = 0.15;
  EXPECT_NE(refused(sliced(d.part.normalized, "", thick)).find("first_layer_height = 0.200"),
            std::string::npos);
  EXPECT_NE(refused(sliced(d.part.normalized, "", thin)).find("layer 2 is 0.150 mm"),
            std::string::npos);
  EXPECT_NE(refused(sliced(d.part.normalized, "; arc_fitting = emit_center\n")).find("arc_fitting"),
            std::string::npos);
  EXPECT_NE(refused(sliced(d.part.normalized, "; spiral_vase = 1\n")).find("spiral_vase"),
            std::string::npos);
  // An arc in the print (a slicer with arc fitting on), named with the setting to change.
  std::string arcs = sliced(d.part.normalized);
  arcs.insert(arcs.find("\n", arcs.find(";TYPE:Perimeter")) + 1, "G2 X100 Y100 I1 J0 E0.1\n");
  EXPECT_NE(refused(arcs).find("is an arc (G2/G3): switch arc fitting off"), std::string::npos);
  // Our own file has no settings block: not a slicer's.
  EXPECT_NE(refused(planar_gcode(d.part.normalized)).find("no settings block"), std::string::npos);
}

// A shell's plan maps only a file on its layers: the core's boundaries, then the shell's; a file
// in even layers, or one whose layers stop short (its settings block kept), is refused by name.
TEST(PostProcess, AShellsPlanRefusesAFileOffItsLayers) {
  const TriangleMesh rib = test::placed(test::rib(), PrintConfig{});
  auto part = prepare_part(rib, make_job(PrintConfig{}), {});
  ASSERT_TRUE(part) << part.error().message;
  ASSERT_GT(part->shell_layers, 0);
  PrintConfig c;
  c.slice.first_layer_height = part->plan.first_layer_height;
  const std::string even = sliced(part->normalized, "", c);
  auto r = post_process_gcode(even, part->plan, {});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("where the plan's shell begins: keep the object's "
                                   "layer-height profile"),
            std::string::npos)
      << r.error().message;
  const std::size_t block = even.find("; prusaslicer_config = begin");
  ASSERT_NE(block, std::string::npos);
  for (const double share : {0.1, 0.5, 0.97}) {
    const std::size_t at =
        even.rfind("\n;LAYER_CHANGE", static_cast<std::size_t>(share * static_cast<double>(block)));
    ASSERT_NE(at, std::string::npos);
    auto cut = post_process_gcode(even.substr(0, at + 1) + even.substr(block), part->plan, {});
    EXPECT_FALSE(cut) << share;
  }
}

// The names object labels give, in the three ways slicers write them.
TEST(PostProcess, ObjectLabelsNameTheParts) {
  EXPECT_EQ(gcode_object_names("; printing object dome id:0 copy 0\nG1 X1\n; stop printing object "
                               "dome id:0 copy 0\n; printing object cube.stl id:1 copy 0\n"),
            (std::vector<std::string>{"dome", "cube"}));
  EXPECT_EQ(gcode_object_names("M486 S0 A\"dome id:0 copy 0\"\nG1 X1\nM486 S-1\nM486 S1 A\"cube\"\n"
                               "M486 S0\n"),
            (std::vector<std::string>{"dome", "cube"}));
  EXPECT_EQ(gcode_object_names("EXCLUDE_OBJECT_DEFINE NAME=dome_id_0_copy_0\n"
                               "EXCLUDE_OBJECT_START NAME=dome_id_0_copy_0\nEXCLUDE_OBJECT_END\n"),
            (std::vector<std::string>{"dome"}));
  EXPECT_TRUE(gcode_object_names("G1 X1 ; printing object dome\n").empty());
  // Bambu Lab's labels give numbers, not names.
  EXPECT_TRUE(gcode_object_names("; start printing object, unique label id: 5\nM624 AQAAAAAAAAA=\n"
                                 "G1 X1\n; stop printing object, unique label id: 5\nM625\n")
                  .empty());
  // post-process: one labelled object is the plan's whatever its name; of several, one must be.
  const Prepared& d = dome();
  const std::string g = sliced(d.part.normalized);
  const auto at = g.find(";LAYER_CHANGE");
  const std::string renamed =
      g.substr(0, at) + "; printing object my dome id:0 copy 0\n" + g.substr(at);
  EXPECT_TRUE(post_process_gcode(renamed, d.part.plan, {}));
  const std::string two = g.substr(0, at) +
                          "; printing object cube id:1 copy 0\n; stop printing "
                          "object cube id:1 copy 0\n; printing object my dome id:0 copy 0\n" +
                          g.substr(at);
  PrintPlan named = d.part.plan;
  named.object = "dome";
  auto r = post_process_gcode(two, named, {});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("the plate's objects are cube, my dome; none is dome, the "
                                   "plan's"),
            std::string::npos)
      << r.error().message;
}

// A part whose top prints as a shell over a planar core (the rib over a void): the part as it
// is with the shell's slab above it, on layers that end on the core's boundaries and then every
// t; the plan's shell reads back bit for bit, moved with the part.
TEST(PrintPlan, AShellIsPreparedAsThePartWithItsSlabAbove) {
  const TriangleMesh rib = test::placed(test::rib(), PrintConfig{});
  auto part = prepare_part(rib, make_job(PrintConfig{}), {});
  ASSERT_TRUE(part) << part.error().message;
  ASSERT_GT(part->shell_layers, 0);
  auto shell = layers::parse_shell_plan_json(part->plan.shell);
  ASSERT_TRUE(shell) << shell.error().message;
  EXPECT_EQ(shell->N, part->shell_layers);
  const double z_s = shell->core.back(), t = shell->t;
  // The rib below, the slab (the layer under the shell, then its N) from z_s up.
  const BoundingBox part_box = bounding_box(rib), box = bounding_box(part->normalized);
  EXPECT_LT(z_s, part_box.max.z());
  EXPECT_NEAR(box.max.z(), z_s + (shell->N + 1) * t, 0.03);
  EXPECT_NEAR(box.min.x(), part_box.min.x(), 1e-9);
  EXPECT_NEAR(box.max.y(), part_box.max.y(), 1e-9);
  EXPECT_EQ(part->plan.first_layer_height, shell->core[1]);
  // The support blocker: over the part from just above z_s (the slab's first layer is sliced
  // at z_s + t/2, the core's last below z_s) to over the slab, a little wider than the part.
  const BoundingBox blocker = bounding_box(part->support_blocker);
  ASSERT_EQ(part->support_blocker.faces.size(), 12u);
  EXPECT_GT(blocker.min.z(), z_s);
  EXPECT_LT(blocker.min.z(), z_s + 0.5 * t);
  EXPECT_GT(blocker.max.z(), box.max.z());
  EXPECT_LT(blocker.min.x(), box.min.x());
  EXPECT_GT(blocker.max.y(), box.max.y());
  EXPECT_NEAR(signed_volume(part->support_blocker), blocker.size().prod(), 1e-6);
  // One layer a boundary: the core's, then every t up to the slab's top.
  const std::string& prof = part->layer_heights_profile;
  EXPECT_EQ(prof.rfind("object_id=1|", 0), 0u);
  const auto layers = static_cast<std::size_t>(std::count(prof.begin(), prof.end(), ';')) / 4;
  EXPECT_EQ(layers, shell->core.size() - 1 + static_cast<std::size_t>(shell->N) + 1);
  // The anchor: the rib's outline at its second layer.
  EXPECT_EQ(part->plan.anchor_z, shell->core[2]);
  ASSERT_GE(part->plan.anchor.size(), 4u);
  auto back = parse_plan_json(plan_json(part->plan));
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->anchor, part->plan.anchor);
  auto moved = layers::parse_shell_plan_json(back->shell, {3, -4});
  ASSERT_TRUE(moved) << moved.error().message;
  EXPECT_EQ(moved->core, shell->core);
  EXPECT_EQ(moved->top.h, shell->top.h);
  EXPECT_EQ(moved->top.origin, shell->top.origin + Vec2(3, -4));
  EXPECT_EQ(moved->reach, shell->reach);
  // What a plan may not say of a shell.
  auto bad = [&](const std::string& from, const std::string& to) {
    std::string f = part->plan.shell;
    const auto at = f.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    f.replace(at, from.size(), to);
    auto r = layers::parse_shell_plan_json(f);
    return r ? std::string() : r.error().message;
  };
  EXPECT_NE(bad("\"t\":", "\"t\":-").find("t must lie"), std::string::npos);
  EXPECT_NE(bad("\"N\":", "\"N\":0,\"x\":").find("N must be"), std::string::npos);
  EXPECT_NE(bad("\"count\":", "\"count\":1,\"x\":").find("must hold"), std::string::npos);
  EXPECT_NE(bad("\"nx\":", "\"nx\":1,\"x\":").find("must hold"), std::string::npos);
}

TEST(PrintPlan, NothingCurvedIsNothingToPrepare) {
  const TriangleMesh box = test::placed(test::box({0, 0, 0}, {20, 20, 10}), PrintConfig{});
  auto part = prepare_part(box, make_job(PrintConfig{}), {});
  ASSERT_FALSE(part);
  EXPECT_EQ(part.error().status, Status::unsupported);
  EXPECT_NE(part.error().message.find("nothing prints curved"), std::string::npos);
}

}  // namespace
}  // namespace nonplanar
