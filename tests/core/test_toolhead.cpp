// The head's allowance a(d) (toolhead.hpp): the round default against its formula, shapes of
// convex slices, the box lower bound the collision search prunes with, the one travel-lift
// rule, and head files (the shipped ones and broken ones).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "nonplanar/config.hpp"
#include "nonplanar/toolhead.hpp"
#include "support/files.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

Toolhead shaped(std::vector<ToolheadSlice> slices) {
  Toolhead t;
  t.shape = std::move(slices);
  return t;
}

std::vector<Vec2> rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

TEST(Toolhead, RoundHeadIsTheConeUnderACylinder) {
  Toolhead t;  // tip 0.4, cone 45°, block r 8 from 4 mm
  const HeadClearance h(t);
  EXPECT_DOUBLE_EQ(h.allowance({0.2, 0}), 0);      // under the tip's flat
  EXPECT_NEAR(h.allowance({1.4, 0}), 1.0, 1e-12);  // the cone's wall at 45°
  EXPECT_NEAR(h.allowance({0, 3.4}), 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(h.allowance({6, 0}), 4.0);          // the block caps the cone
  EXPECT_TRUE(std::isinf(h.allowance({8.01, 0})));     // beyond the block: nothing
  EXPECT_DOUBLE_EQ(h.block_allowance({1.4, 0}), 4.0);  // the block alone
  EXPECT_DOUBLE_EQ(h.reach(), 8.0);
  t.cone_angle_deg = 15;
  EXPECT_NEAR(HeadClearance(t).allowance({2.4, 0}), 2.0 * std::tan(15 * M_PI / 180), 1e-12);
}

TEST(Toolhead, ReachUnderAHeightIsTheConesOrTheBlocks) {
  Toolhead t;  // tip 0.4, cone 45°, block r 8 from 4 mm
  EXPECT_NEAR(t.reach_under(0), 0.4, 1e-12);
  EXPECT_NEAR(t.reach_under(1.5), 1.9, 1e-12);  // the cone's wall at 45°
  EXPECT_NEAR(t.reach_under(4), 4.4, 1e-12);    // the block starts above 4 mm
  EXPECT_DOUBLE_EQ(t.reach_under(4.01), 8.0);
  EXPECT_DOUBLE_EQ(t.reach_under(100), t.reach());
  Toolhead s;  // a duct 20 mm off the nozzle from 2 mm up, a block over it from 5 mm
  s.shape = {{2, {{{18, -3}, {22, -3}, {22, 3}, {18, 3}}}},
             {5, {{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}}}};
  EXPECT_NEAR(s.reach_under(1), 1.4, 1e-12);                    // the cone alone
  EXPECT_NEAR(s.reach_under(3), std::hypot(22.0, 3.0), 1e-12);  // and the duct
  EXPECT_NEAR(s.reach_under(100), s.reach(), 1e-12);
}

TEST(Toolhead, ShapeSlicesCoverTheirPolygonsFromTheirHeightUp) {
  // A fan duct 2 mm up on the right, a probe 1 mm up at the back-left, the block at 3 mm.
  const Toolhead t = shaped({{3, {rect(-6, -6, 6, 6)}},
                             {2, {rect(5, -10, 20, 10)}},
                             {1, {{{-22, -9}, {-18, -5}, {-22, -1}, {-26, -5}}}}});
  const HeadClearance h(t);
  EXPECT_DOUBLE_EQ(t.cone_top(), 3);
  EXPECT_DOUBLE_EQ(t.clearance(), 1);
  EXPECT_NEAR(h.allowance({1.4, 0}), 1.0, 1e-12);    // cone, below the block
  EXPECT_DOUBLE_EQ(h.allowance({0, 5}), 3);          // block caps the cone
  EXPECT_DOUBLE_EQ(h.allowance({10, 0}), 2);         // the duct
  EXPECT_DOUBLE_EQ(h.allowance({-22, -5}), 1);       // the probe
  EXPECT_TRUE(std::isinf(h.allowance({-22, 5})));    // beside it: free
  EXPECT_TRUE(std::isinf(h.allowance({0, -8})));     // beyond the block, under no slice
  EXPECT_DOUBLE_EQ(h.block_allowance({1.4, 0}), 3);  // no cone
  EXPECT_NEAR(h.reach(), std::hypot(26, 5), 1e-12);  // the probe's far corner
}

TEST(Toolhead, SlicesAboveTheTallestMaterialAreLeftOut) {
  // A gantry beam 17 mm up across the bed, over a block 3 mm up.
  const Toolhead t = shaped({{3, {rect(-6, -6, 6, 6)}}, {17, {rect(-300, -35, 300, -21)}}});
  const HeadClearance all(t), low(t, 10.0), flat(t, 2.0);
  EXPECT_NEAR(all.reach(), std::hypot(300, 35), 1e-9);
  EXPECT_DOUBLE_EQ(all.allowance({200, -30}), 17);
  // A 10 mm print cannot reach the beam: it is dropped, reach is the block's corner.
  EXPECT_NEAR(low.reach(), std::hypot(6, 6), 1e-12);
  EXPECT_TRUE(std::isinf(low.allowance({200, -30})));
  EXPECT_DOUBLE_EQ(low.allowance({0, 5}), 3);
  // 2 mm tall: only the cone, up to 2 mm (reach 0.4 + 2 / tan 45°); the shape stays a shape
  // (no round block appears when every slice is dropped).
  EXPECT_NEAR(flat.reach(), 2.4, 1e-12);
  EXPECT_NEAR(flat.allowance({1.4, 0}), 1.0, 1e-12);
  EXPECT_TRUE(std::isinf(flat.allowance({0, 5})));
}

TEST(Toolhead, BoxLowerBoundNeverExceedsTheAllowanceInside) {
  const Toolhead t = shaped(
      {{3.5, {rect(-7, -7, 7, 7)}}, {2, {rect(6, -10, 20, 10)}}, {1, {rect(-26, -9, -18, -1)}}});
  for (const Toolhead& head : {t, Toolhead{}}) {
    const HeadClearance h(head);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-25, 25), s(0.1, 6);
    int tight = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec2 lo(u(rng), u(rng)), hi = lo + Vec2(s(rng), s(rng));
      const double bound = h.allowance_lower_bound(lo, hi);
      double least = std::numeric_limits<double>::infinity();
      for (int a = 0; a <= 20; ++a)
        for (int b = 0; b <= 20; ++b)
          least = std::min(least, h.allowance(lo + (hi - lo).cwiseProduct(Vec2(a, b) / 20.0)));
      ASSERT_LE(bound, least + 1e-12) << lo.transpose() << " / " << hi.transpose();
      tight += bound == least;
    }
    EXPECT_GT(tight, 500);  // a bound of 0 everywhere would pass the line above
  }
}

TEST(Toolhead, TravelHeight) {
  const Vec3 a(0, 0, 5), b(10, 0, 5.5);
  EXPECT_DOUBLE_EQ(travel_height(a, b, 7, 0.5, 0.4, 0.3), 7.3);  // long: over the layer's top
  EXPECT_DOUBLE_EQ(travel_height(a, b, 5, 0.5, 0.4, 0.6), 6.1);  // ... or its ends, + lift
  // A 0.45 mm hop on a layer of slope 0.5: 0.5 · (0.225 + 0.4) + 0.05 above the higher end.
  EXPECT_NEAR(travel_height(a, {0.45, 0, 5.02}, 9, 0.5, 0.4, 0.3), 5.02 + 0.3625, 1e-12);
  EXPECT_TRUE(std::isnan(travel_height(a, {0.45, 0, 5}, 9, 0.05, 0.4, 0.3)));  // flat: none
}

TEST(Toolhead, ShippedHeadsLoadAndReachFarther) {
  const auto dir =
      std::filesystem::path(NONPLANAR_TEST_DATA).parent_path().parent_path() / "toolheads";
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    auto shape = load_toolhead_shape(e.path().string());
    ASSERT_TRUE(shape) << shape.error().message;
    Toolhead t;
    t.shape = *shape;
    EXPECT_GE(t.reach(), 8.0) << e.path();
    EXPECT_GT(t.cone_top(), 0) << e.path();
    ++n;
  }
  EXPECT_GE(n, 4);
  // By bare name, and through the profile key.
  ASSERT_TRUE(load_toolhead_shape("prusa-mk4"));
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "toolhead_shape", "prusa-mk3s"));
  EXPECT_EQ(c.toolhead.shape.size(), 4u);
  EXPECT_DOUBLE_EQ(c.toolhead.clearance(), 1.0);  // the PINDA probe
  EXPECT_DOUBLE_EQ(c.toolhead.cone_top(), 2.0);   // the body over the nozzle
  ASSERT_TRUE(set_config_value(c, "toolhead_shape", ""));
  EXPECT_TRUE(c.toolhead.shape.empty());
  // round.json is the default head written as a 48-gon inside its circle.
  auto round = load_toolhead_shape("round");
  ASSERT_TRUE(round);
  Toolhead r;
  r.shape = *round;
  const HeadClearance hr(r), hd{Toolhead{}};
  for (const Vec2& d : {Vec2(1, 0), Vec2(3, 3), Vec2(0, 7.8), Vec2(-8.5, 0)})
    EXPECT_EQ(hr.allowance(d), hd.allowance(d)) << d.transpose();
}

TEST(Toolhead, BrokenHeadFilesSayWhatIsWrong) {
  const std::pair<const char*, const char*> cases[] = {
      {"{", "not valid JSON"},
      {"[]", "\"slices\" array"},
      {R"({"slices": []})", "1 to 64 slices"},
      {R"({"slices": [{"height": -1, "polygons": ["0,0;1,0;0,1"]}]})", "slice 1: \"height\""},
      {R"({"slices": [{"height": "x", "polygons": ["0,0;1,0;0,1"]}]})", "\"height\""},
      {R"({"slices": [{"height": 1, "polygons": []}]})", "1 to 64 polygons"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;1,0"]}]})", "3 to 256 vertices"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;1,0;1"]}]})", "odd number"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;a,0;1,1"]}]})", "'a' is not a number"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;4,0;1,1;0,4"]}]})", "not convex"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;1,1;2,2"]}]})", "no area"},
      {R"({"slices": [{"height": 1, "polygons": ["0,0;1e9,0;0,1"]}]})", "within 1000 mm"},
      {R"({"slices": [{"height": 1, "type": "cone", "polygons": ["0,0;1,0;0,1"]}]})",
       "convex or box"},
      {R"({"slices": [{"height": 1, "polygons": [[[0,0],[1],[0,1]]]}]})", "[x, y]"},
  };
  for (const auto& [text, why] : cases) {
    auto r = parse_toolhead_shape(text);
    ASSERT_FALSE(r) << text;
    EXPECT_NE(r.error().message.find(why), std::string::npos) << text << ": " << r.error().message;
  }
  // A file names itself; a missing name says where it looked.
  const auto dir = test::temp_dir("toolhead_files");
  test::write_bytes(dir / "h.json", R"({"slices": [{"height": 1, "polygons": ["0,0;1,0;1"]}]})");
  auto f = load_toolhead_shape((dir / "h.json").string());
  ASSERT_FALSE(f);
  EXPECT_NE(f.error().message.find("h.json: slice 1, polygon 1: odd"), std::string::npos)
      << f.error().message;
  auto missing = load_toolhead_shape("no-such-head");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no-such-head"), std::string::npos);
  PrintConfig c;
  EXPECT_FALSE(set_config_value(c, "toolhead_shape", "no-such-head"));
}

TEST(Toolhead, ProfileKeysAreValidated) {
  PrintConfig c;
  ASSERT_TRUE(set_config_value(c, "nozzle_cone_angle", "30"));
  ASSERT_TRUE(set_config_value(c, "heater_block_radius", "11"));
  EXPECT_DOUBLE_EQ(c.toolhead.cone_angle_deg, 30);
  EXPECT_DOUBLE_EQ(c.toolhead.block_radius, 11);
  EXPECT_TRUE(is_nonplanar_key("heater_block_clearance"));
  EXPECT_FALSE(is_nonplanar_key("layer_height"));
  for (const auto& [k, v] :
       std::vector<std::pair<std::string, std::string>>{{"nozzle_cone_angle", "90"},
                                                        {"nozzle_cone_angle", "2"},
                                                        {"nozzle_tip_radius", "0"},
                                                        {"heater_block_radius", "0.1"},
                                                        {"heater_block_clearance", "-1"},
                                                        {"heater_block_clearance", "nan"}}) {
    PrintConfig d;
    const auto r = set_config_value(d, k, v);
    const auto ok = r ? validate_config(d) : Expected<void>(r.error());
    EXPECT_FALSE(ok) << k << "=" << v;
  }
}

}  // namespace
}  // namespace nonplanar
