// The shell over a planar core (src/layers/shell_plan.hpp) on a wing rib whose top rises from
// 0.3 mm to 12.3 mm: the core's stairs under the shell, the thickness of the layer that fills
// them, and the parts it must refuse.
#include <gtest/gtest.h>

#include <atomic>

#include "nonplanar/io.hpp"

#include <cmath>

#include "layers/shell_plan.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

double rib_top(double x) {
  return 0.3 + 12 * std::sin(M_PI * x / 100);
}

std::vector<int> curved(const Analysis& a) {
  std::vector<int> ids;
  for (std::size_t i = 0; i < a.patches.size(); ++i)
    if (a.patches[i].needs_nonplanar()) ids.push_back(static_cast<int>(i));
  return ids;
}

// The plan at the default settings but four curved layers (two by default), as these tests'
// heights were worked out for.
layers::ShellPlan plan(const TriangleMesh& m, int layers = 4) {
  const Analysis a = *analyze(m, {}, {});
  LayerParams lp;
  lp.shell_layers = layers;
  return layers::plan_shell(m, a, curved(a), lp);
}

// A closed box turned inside out: a void inside a solid (its floor faces up, its ceiling down).
TriangleMesh void_box(const Vec3& lo, const Vec3& hi) {
  TriangleMesh b = test::box(lo, hi);
  for (auto& f : b.faces) std::swap(f[1], f[2]);
  return b;
}

TEST(ShellPlan, RibStairsStayInsideTheLimits) {
  const LayerParams lp;
  const layers::ShellPlan s = plan(test::rib());
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  EXPECT_EQ(s.N, 4);
  EXPECT_DOUBLE_EQ(s.t, lp.layer_height);
  EXPECT_NEAR(s.reach, lp.layer_height - lp.min_layer_height - 0.01, 1e-12);
  // Core boundaries from the bed, each step in [h_min, h_max − h_min − 0.02].
  ASSERT_GT(s.core.size(), 50u);
  EXPECT_EQ(s.core.front(), 0.0);
  for (std::size_t k = 1; k < s.core.size(); ++k) {
    EXPECT_GE(s.core[k] - s.core[k - 1], lp.min_layer_height - 1e-9) << k;
    EXPECT_LE(s.core[k] - s.core[k - 1], 0.18 + 1e-9) << k;
  }
  int filled = 0;
  for (double x = 0.25; x < 80; x += 0.37)
    for (double y = 0.5; y < 12; y += 1.1) {
      // H is the rib's facets: within their sag (κ L² / 8 < 0.4 µm) of the analytic top.
      EXPECT_NEAR(s.top.height(x, y), rib_top(x), 2e-3) << x;
      const double B = s.bottom(x, y), Zc = s.core_top(x, y);
      EXPECT_LE(Zc, std::max(B + s.reach, 0.0) + 1e-9);
      if (B + s.reach >= s.core[1]) {
        EXPECT_GT(Zc, B + s.reach - 0.18 - 1e-9) << x;
      }
      // The lowest shell layer, where it exists (its middle above the bed), fills the
      // stairs within [h_min + 0.01, h_max − 0.01].
      if (B + 0.5 * s.t > 0) {
        const double t0 = s.thickness(0, x, y);
        EXPECT_GE(t0, lp.min_layer_height + 0.01 - 1e-9) << x;
        EXPECT_LE(t0, lp.max_layer_height - 0.01 + 1e-9) << x;
        filled += B + s.reach >= s.core[1];
      }
      for (int j = 1; j < s.N; ++j)
        if (s.layer_top(j - 1, x, y) >= 0) {
          EXPECT_NEAR(s.thickness(j, x, y), s.t, 1e-12);
        }
    }
  EXPECT_GT(filled, 1000);  // most of the rib has core under its shell
}

// Ctrl-C while shells are planned: the plan stops between its steps (the bunny's shells took
// 4 s under ThreadSanitizer, and an interrupt's 10 s of grace ran out in CI), and
// choose_shells passes the flag on.
TEST(ShellPlan, StopsWhenCancelled) {
  const TriangleMesh m = test::rib();
  const Analysis a = *analyze(m, {}, {});
  ASSERT_TRUE(layers::plan_shell(m, a, curved(a), LayerParams{}).refused.empty());
  std::atomic<bool> stop{true};
  Context cancelled;
  cancelled.cancel_flag = &stop;
  EXPECT_EQ(layers::plan_shell(m, a, curved(a), LayerParams{}, 0, false, &cancelled).refused,
            "cancelled");
  layers::ShellChoice c;
  c.cancel = &cancelled;
  EXPECT_EQ(layers::choose_shells(m, a, LayerParams{}, c).front().refused, "cancelled");
}

TEST(ShellPlan, CoreLandsOnAFlatFloorInside) {
  TriangleMesh m = test::rib();
  test::append(m, void_box({20, 3, 2.13}, {40, 9, 4}));
  const layers::ShellPlan s = plan(m);
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  bool landed = false;
  for (double z : s.core) landed |= std::abs(z - 2.13) < 1e-9;
  EXPECT_TRUE(landed);
}

TEST(ShellPlan, RefusesWhatTheShellCannotCover) {
  // A slab over the whole rib: nothing of its top is left to print curved.
  TriangleMesh covered = test::rib();
  test::append(covered, test::box({-1, -1, 13}, {81, 13, 14}));
  const std::string stands = plan(covered).refused;
  EXPECT_NE(stands.find("the part stands above most of the curved top"), std::string::npos)
      << stands;
}

// A void whose ceiling is 0.25 mm under the top at x = 20 (H = 7.35 mm): no core layer fits
// between it and even a one-layer shell. The shell leaves to the core, which prints it planar,
// only where the ceiling comes within N·t + 0.5 = 1.3 mm under H (x < 23.6, where H = 8.4 mm),
// and says so (it was refused whole, and then the void's whole footprint was left out).
TEST(ShellPlan, LeavesOutWhereAnOverhangLiesUnderIt) {
  TriangleMesh hollow = test::rib();
  test::append(hollow, void_box({20, 3, 5}, {40, 9, 7.1}));
  const layers::ShellPlan s = plan(hollow);
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  EXPECT_EQ(s.N, 4);
  EXPECT_NE(s.left_out.find("an overhang lies under the shell"), std::string::npos) << s.left_out;
  EXPECT_FALSE(s.in_region(21, 6));
  EXPECT_FALSE(s.in_region(23, 6));
  EXPECT_TRUE(s.in_region(25, 6));  // the ceiling 1.9 mm under the top: the core bridges it
  EXPECT_TRUE(s.in_region(35, 6));
  EXPECT_TRUE(s.in_region(70, 6));
  EXPECT_TRUE(s.in_region(10, 6));
}

// A tower against the rib's side (x 30-40), where the rib's top runs from 10.0 to 11.7 mm
// along its foot: the shell prints where nothing stands above it, and next to the tower its
// points may be printed no more than the head allows before or after the tower's layers there
// (the slack s: the cone's allowance, grown no faster than 0.15 mm per mm, + h/4).
TEST(ShellPlan, BesideATowerPrintsWhereNothingStandsAboveWithALittleSlack) {
  TriangleMesh tower = test::rib();
  test::append(tower, test::box({30, 12, 0}, {40, 16, 14}));
  const layers::ShellPlan s = plan(tower);
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  ASSERT_FALSE(s.region.empty());
  EXPECT_FALSE(s.in_region(35, 14));  // the tower
  EXPECT_TRUE(s.in_region(35, 6));
  EXPECT_TRUE(s.in_region(70, 6));
  // Slack 0.05 mm (h/4) at the tower's foot, growing no faster than 0.15 mm per mm.
  EXPECT_NEAR(s.slack.height(35, 11.9), 0.05, 0.03);
  EXPECT_LE(s.slack.height(35, 6), 0.05 + 0.15 * 6 + 0.03);
  EXPECT_GT(s.slack.height(35, 6), s.slack.height(35, 11));
  // So a point next to it is printed close to its own height, one far off at the target.
  const double u = s.top.height(35, 11.8);
  EXPECT_NEAR(s.slot_level(35, 11.8, u), u, 0.1);
}

// One slicer run prints a shell over the whole top or none (whole_only): the rib with the tower
// against it is refused with the reason given, as soon as R is known (no core planned); the
// rib alone, which nothing stands above, plans as without it.
TEST(ShellPlan, OneRunRefusesAShellThePartStandsAbove) {
  TriangleMesh tower = test::rib();
  test::append(tower, test::box({30, 12, 0}, {40, 16, 14}));
  const Analysis a = *analyze(tower, {}, {});
  const layers::ShellPlan s =
      layers::plan_shell(tower, a, curved(a), {}, 0, false, nullptr, "one run");
  EXPECT_EQ(s.refused, "one run");
  EXPECT_FALSE(s.region.empty());
  EXPECT_TRUE(s.core.empty());
  EXPECT_EQ(layers::choose_shell(tower, a, {}, "one run").refused, "one run");
  const TriangleMesh rib = test::rib();
  const Analysis b = *analyze(rib, {}, {});
  const layers::ShellPlan alone =
      layers::plan_shell(rib, b, curved(b), {}, 0, false, nullptr, "one run");
  const layers::ShellPlan any = layers::plan_shell(rib, b, curved(b), {});
  ASSERT_TRUE(alone.refused.empty()) << alone.refused;
  EXPECT_TRUE(alone.region.empty());
  EXPECT_EQ(alone.core, any.core);
  EXPECT_EQ(alone.N, any.N);
}

// A void whose ceiling is 0.3 mm under the four-layer shell's bottom at x = 20 (B = 6.55 mm,
// ceiling 6.25 mm): the shell takes three layers, whose bottom (6.75 mm) leaves room for a core
// layer between it and the ceiling (1.5 h_c − a + 0.05 = 0.23 mm at the defaults).
TEST(ShellPlan, TakesFewerLayersOverAThinWall) {
  TriangleMesh hollow = test::rib();
  test::append(hollow, void_box({20, 3, 5}, {40, 9, 6.25}));
  const layers::ShellPlan s = plan(hollow);
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  EXPECT_EQ(s.N, 3);
  EXPECT_EQ(plan(test::rib()).N, 4);
  EXPECT_EQ(plan(test::rib(), 0).N, 2);  // automatic: 0.4 mm of layers
  EXPECT_GE(s.bottom(20, 6) - 6.25, 0.23 - 1e-6);
}

// A cone's tip: the facets round its apex touch a curvature jump (the apex holds all of the
// cone's angle deficit), so no patch takes them and no stack could follow them, but the shell
// follows the facets themselves: its top H runs up to the apex, and the shell prints there.
// (Before, H over the tip carried the patch's rim inward, 0.5 mm under the apex, and the core
// printed the tip planar because the part stood above H there.)
TEST(ShellPlan, FollowsFacetsThatTouchACurvatureJump) {
  // Top 12 − 0.36·r about (20, 20) (20° slopes), the apex on a grid vertex.
  const TriangleMesh cone = test::height_field_solid(
      [](double x, double y) { return 12 - 0.36 * std::hypot(x - 20, y - 20); }, 0, 40, 0, 40, 40,
      40);
  const Analysis a = *analyze(cone, {}, {});
  ASSERT_GT(a.discontinuous_faces, 0u);
  const layers::ShellPlan s = plan(cone);
  ASSERT_TRUE(s.refused.empty()) << s.refused;
  EXPECT_NEAR(s.top.height(20, 20), 12.0, 1e-6);
  EXPECT_NEAR(s.top.height(20.5, 20), 12 - 0.36 * 0.5, 1e-6);
  EXPECT_TRUE(s.in_region(20, 20));
  EXPECT_TRUE(s.left_out.empty()) << s.left_out;
}

// The CurviSlicer ankle base: its heel's curved top is ringed by a rim standing above it, so a
// shell over both curved patches would follow the rim up in bands over 92 % of the heel (printed
// as 402 layers and 1h33m against the planar 85 and 32m): refused. The rim's own tilted top
// gets the shell alone. The tilted bore through it leans under the rim (faces 23° off the
// vertical, printed over each other as planar layers print them): not an overhang the shell
// would rest on, which had refused this shell too.
TEST(ShellPlan, RefusesAShellMostlyPrintedInBands) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_curvislicer_anklebase_small.stl", {}, {});
  ASSERT_TRUE(m);
  const Analysis a = *analyze(m->mesh, {}, {});
  ASSERT_EQ(a.patches.size(), 4u);
  ASSERT_TRUE(a.patches[0].needs_nonplanar() && a.patches[1].needs_nonplanar());
  LayerParams half;  // the default allows any share in bands
  half.shell_max_banded = 0.5;
  const std::string why = layers::plan_shell(m->mesh, a, {0, 1}, half).refused;
  EXPECT_NE(why.find("in bands"), std::string::npos) << why;
  const layers::ShellPlan rim = layers::choose_shell(m->mesh, a, half);
  EXPECT_TRUE(rim.refused.empty()) << rim.refused;
  EXPECT_EQ(rim.patches, std::vector<int>{0});
  // It says why it is not the wider one (slice's notice and `layers` print it).
  EXPECT_EQ(rim.narrowed, "a shell over patches 0, 1: " + why);
  EXPECT_TRUE(layers::plan_shell(m->mesh, a, {0}, half).narrowed.empty());
  // The limit is a setting (shell_max_banded): at 1, the default, the shell over both is
  // planned, banded over 69 % of them.
  const LayerParams any;
  const layers::ShellPlan both = layers::plan_shell(m->mesh, a, {0, 1}, any);
  EXPECT_TRUE(both.refused.empty()) << both.refused;
  EXPECT_EQ(layers::choose_shell(m->mesh, a, any).patches, (std::vector<int>{0, 1}));
  // choose_shells weighs the banded shell against shells apart: the inner ring alone follows
  // 57 % of the curved area, so the banded one is kept.
  const std::vector<layers::ShellPlan> chosen = layers::choose_shells(m->mesh, a, any);
  ASSERT_EQ(chosen.size(), 1u);
  EXPECT_EQ(chosen.front().patches, (std::vector<int>{0, 1}));
  EXPECT_NEAR(chosen.front().banded, 0.69, 0.01);
}

// The core's boundaries are foreseen from the analysis where the part stands above a curved
// top (a tower on the rib), as its shells then plan them, so that an engine can slice the core
// while they are planned; nothing is foreseen where nothing stands above it (the rib alone).
TEST(ShellPlan, ForeseesTheCoreOfShellsThePartStandsAbove) {
  const TriangleMesh rib = test::rib();
  const Analysis a = *analyze(rib, {}, {});
  EXPECT_FALSE(layers::region_shells_core(rib, a, {}));
  TriangleMesh tower = test::rib();
  test::append(tower, test::box({45, 3, 0}, {55, 9, 20}));
  const Analysis b = *analyze(tower, {}, {});
  const auto core = layers::region_shells_core(tower, b, {});
  ASSERT_TRUE(core);
  const std::vector<layers::ShellPlan> plans = layers::choose_shells(tower, b, {});
  ASSERT_TRUE(plans.front().refused.empty()) << plans.front().refused;
  EXPECT_FALSE(plans.front().region.empty());
  EXPECT_EQ(plans.front().core, *core);
  EXPECT_NEAR(core->back(), 20.0, 0.2);  // up to the tower's top
}

// choose_shells weighs the bunny's shell, banded over 52 % of its patches, against the shells
// apart at shell_max_banded 0.5, and takes those (they follow 86 % of its area). Their first is
// the group near the largest patch that choose_first planned beside the banded shell, taken as
// planned there rather than planned again: as choose_shell plans it at 0.5, bands, slack and
// all, its notice naming what was weighed instead of the setting.
TEST(ShellPlan, TheShellsApartBeginWithTheGroupPlannedBesideTheBandedOne) {
  const auto dir = test::shared_models();
  if (dir.empty()) GTEST_SKIP() << "../shared/models not present";
  auto m = load_mesh(dir / "np_stanford_bunny_closed_compas.stl", {}, {});
  ASSERT_TRUE(m);
  const Analysis a = *analyze(m->mesh, {}, {});
  const std::vector<layers::ShellPlan> chosen = layers::choose_shells(m->mesh, a, {});
  ASSERT_EQ(chosen.size(), 4u);
  LayerParams half;
  half.shell_max_banded = 0.5;
  const layers::ShellPlan first = layers::choose_shell(m->mesh, a, half);
  ASSERT_TRUE(first.refused.empty()) << first.refused;
  EXPECT_EQ(chosen[0].patches, first.patches);
  EXPECT_EQ(chosen[0].core, first.core);
  EXPECT_EQ(chosen[0].region.in, first.region.in);
  EXPECT_EQ(chosen[0].slack.h, first.slack.h);
  EXPECT_EQ(chosen[0].banded, first.banded);
  const auto k = first.narrowed.find("shell_max_banded 0.50");
  ASSERT_NE(k, std::string::npos) << first.narrowed;
  EXPECT_EQ(chosen[0].narrowed.substr(0, k), first.narrowed.substr(0, k));
  EXPECT_NE(chosen[0].narrowed.find("shells apart follow 86 % of its area"), std::string::npos)
      << chosen[0].narrowed;
}

}  // namespace
}  // namespace nonplanar
