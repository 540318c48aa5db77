// The shell route through an external engine (src/engine/shell_engine.cpp): the slab cut
// from the normalised mesh, and the core's layers cut back (map_foreign_gcode's clip).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>

#include "engine/shell_engine.hpp"
#include "nonplanar/deform.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

double area(const TriangleMesh& m) {
  double a = 0;
  for (const auto& f : m.faces) {
    const Vec3& p = m.vertices[static_cast<std::size_t>(f[0])];
    a += 0.5 * (m.vertices[static_cast<std::size_t>(f[1])] - p)
                   .cross(m.vertices[static_cast<std::size_t>(f[2])] - p)
                   .norm();
  }
  return a;
}

// Edges used by one face only: (length, all on z0).
std::pair<double, bool> open_edges(const TriangleMesh& m, double z0) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : m.faces)
    for (int k = 0; k < 3; ++k) {
      int a = f[static_cast<std::size_t>(k)], b = f[static_cast<std::size_t>((k + 1) % 3)];
      if (a > b) std::swap(a, b);
      ++uses[{a, b}];
    }
  double len = 0;
  bool on = true;
  for (const auto& [e, n] : uses) {
    if (n != 1) continue;
    const Vec3& p = m.vertices[static_cast<std::size_t>(e.first)];
    const Vec3& q = m.vertices[static_cast<std::size_t>(e.second)];
    len += (q - p).norm();
    on = on && std::abs(p.z() - z0) < 1e-12 && std::abs(q.z() - z0) < 1e-12;
  }
  return {len, on};
}

TEST(CutBelow, KeepsTheMeshAboveOpenAlongTheCut) {
  const TriangleMesh box = test::box({0, 0, 0}, {10, 10, 10});
  const TriangleMesh cut = cut_below(box, 2.5);
  for (const Vec3& v : cut.vertices) EXPECT_GE(v.z(), 2.5);
  EXPECT_NEAR(area(cut), 100 + 4 * 10 * 7.5, 1e-9);  // the top and the walls above 2.5
  const auto [len, on] = open_edges(cut, 2.5);
  EXPECT_NEAR(len, 40.0, 1e-9);  // the cut's outline, and nothing else open
  EXPECT_TRUE(on);
  // A cut under the mesh keeps it whole and closed.
  const TriangleMesh whole = cut_below(box, -1);
  EXPECT_NEAR(area(whole), 600, 1e-9);
  EXPECT_NEAR(open_edges(whole, -1).first, 0.0, 1e-12);
  EXPECT_TRUE(cut_below(box, 11).faces.empty());
}

// Keeps x <= 4 on layers up to 0.3 mm, nothing above.
class LeftOfFour final : public LayerClip {
 public:
  Cover cover(double z) const override { return z < 0.3 ? Cover::some : Cover::none; }
  double margin(double x, double, double) const override { return 4 - x; }
};

TEST(MapForeignGcode, ClipsLayersAndEntersFromAGivenStart) {
  const std::string g =
      "M83\nM106 S100\n"
      ";LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 Z0.2 F600\nG1 X0 Y0 F6000\n"
      "G1 E-1 F2400\nG1 E1 F2400\n"
      ";TYPE:Perimeter\nG1 X10 Y0 E1 F1200\nG1 X10 Y10 E1\nG1 E-0.8 F2400\n"
      ";LAYER_CHANGE\n;Z:0.4\n;HEIGHT:0.2\nG1 Z0.4\nM106 S200\nM104 S210\n"
      ";TYPE:Perimeter\nG1 X0 Y10 E1\n"
      ";TYPE:Custom\nM107\nG28\n";
  const auto field = planar_field({});
  const LeftOfFour clip;
  ForeignMapOptions o;
  o.clip = &clip;
  o.start = Vec3(50, 50, 5);
  o.start_retracted = 0.5;
  auto r = map_foreign_gcode(g, *field, {}, {}, o);
  ASSERT_TRUE(r) << r.error().message;
  const std::string t = r->text();
  // The kept piece extrudes its share; the rest is travel (6 mm, then the whole next move),
  // retracted once around both.
  EXPECT_NE(t.find("G1 X4.000 Y0.000 E0.40000 F1200\nG1 E-1.00000 F2400\nG1 X10.000 Y0.000 "
                   "F1200\nG1 X10.000 Y10.000 F1200\nG1 E1.00000 F2400\nG1 E-0.80000 F2400"),
            std::string::npos)
      << t;
  ASSERT_EQ(r->layers.size(), 1u);  // the second layer is left out ...
  double len = 0;
  for (const ExtrusionPath& p : r->layers[0].paths)
    for (std::size_t k = 1; k < p.points.size(); ++k) len += (p.points[k] - p.points[k - 1]).norm();
  EXPECT_NEAR(len, 4.0, 1e-6);
  EXPECT_EQ(t.find("M106 S200"), std::string::npos);  // ... but for its temperature
  EXPECT_NE(t.find("M104 S210"), std::string::npos);
  // Entered from the given start: the Z move stays over it; the retraction owed is given back.
  EXPECT_NE(t.find(";HEIGHT:0.200\nG1 Z0.200 F600\nG1 X0.000 Y0.000 F6000\nG1 E-0.50000 F2400"),
            std::string::npos)
      << t;
  // The three blocks the shell route joins by.
  EXPECT_EQ(r->start, "M83\nM106 S100\n");
  EXPECT_EQ(r->print.rfind(";LAYER_CHANGE", 0), 0u);
  EXPECT_EQ(r->end, ";TYPE:Custom\nM107\nG28\n");
  EXPECT_NEAR(r->retracted, 0.8, 1e-9);
  EXPECT_TRUE(r->end_at.isApprox(Vec3(10, 10, 0.2)));
  EXPECT_EQ(r->fan_at_print, "M106 S100");
  EXPECT_TRUE(r->relative_e_at_print);
}

// Keeps where a zigzag is over 0: margin 1.5 − |x mod 8 − 4| + 0.05·y, as steep along x as
// its bound, hypot(1, 0.05), allows (a step skipped too many would cross a cut); counts the
// margins looked up. With the bound told, moves are cut exactly where they are without it,
// from far fewer margins (a third: each cut still takes 30 to bisect).
class Zigzag final : public LayerClip {
 public:
  explicit Zigzag(bool tell) : tell_(tell) {}
  Cover cover(double) const override { return Cover::some; }
  double margin(double x, double y, double) const override {
    ++looked;
    return 1.5 - std::abs(std::fmod(x + 100, 8.0) - 4) + 0.05 * y;
  }
  double slope_bound(const Vec2& lo, const Vec2& hi, double z) const override {
    return tell_ ? std::hypot(1.0, 0.05) : LayerClip::slope_bound(lo, hi, z);
  }
  mutable std::atomic<long> looked{0};  // (layers are cut side by side)

 private:
  bool tell_;
};

// Infill lines across the zigzag, 30 mm long, 0.45 mm apart, on `layers` layers.
std::string zigzag_infill(int layers) {
  std::string g = "M83\n";
  for (int layer = 0; layer < layers; ++layer) {
    const double z = 0.2 * (layer + 1);
    g += ";LAYER_CHANGE\n;Z:" + std::to_string(z) + "\n;HEIGHT:0.2\nG1 Z" + std::to_string(z) +
         " F600\nG1 X0 Y0 F6000\n;TYPE:Internal infill\n";
    for (int k = 0; k < 20; ++k) {
      const double y = 0.45 * k;
      g += "G1 X" + std::to_string(k % 2 ? 0 : 30) + " Y" + std::to_string(y) + " E1 F1200\n";
      g += "G1 X" + std::to_string(k % 2 ? 0 : 30) + " Y" + std::to_string(y + 0.45) + " E0.02\n";
    }
  }
  return g;
}

TEST(MapForeignGcode, AClipsSlopeBoundSkipsStepsNotCuts) {
  const std::string g = zigzag_infill(2);
  const auto field = planar_field({});
  auto run = [&](const Zigzag& clip) {
    ForeignMapOptions o;
    o.clip = &clip;
    auto r = map_foreign_gcode(g, *field, {}, {}, o);
    EXPECT_TRUE(r) << r.error().message;
    return r ? r->text() : std::string();
  };
  const Zigzag every_step(false), bounded(true);
  const std::string a = run(every_step), b = run(bounded);
  EXPECT_TRUE(a == b);                                   // (not EXPECT_EQ: 20 kB of text)
  EXPECT_GT(std::count(a.begin(), a.end(), '\n'), 200);  // cut many times over
  EXPECT_LT(bounded.looked * 2, every_step.looked) << bounded.looked << " " << every_step.looked;
}

// The clip's limit on the margins looked up (most_clip_samples) stops the map at the line where
// the count passes it, as when the layers were cut one by one: cut side by side, 32 layers at
// once, it stops at the same line as one layer at a time, wherever in the file the limit falls.
// The margins looked up side by side stay within twice the limit (the layers stop once their
// shared count passes it; the layer it stopped in is cut again in turn, to find the line).
TEST(MapForeignGcode, TheClipsLimitStopsAtTheLineTheCountPassesIt) {
  const std::string g = zigzag_infill(12);
  const auto field = planar_field({});
  auto run = [&](const Zigzag& clip, std::size_t most, std::size_t at_once) {
    MapBackParams mp;
    mp.passes.most_clip_samples = most;
    ForeignMapOptions o;
    o.clip = &clip;
    o.layers_at_once = at_once;
    auto r = map_foreign_gcode(g, *field, mp, {}, o);
    return r ? std::string("ok") : r.error().message;
  };
  const Zigzag all(true);
  ASSERT_EQ(run(all, 50'000'000, 32), "ok");
  const auto total = static_cast<std::size_t>(all.looked.load());
  std::string last;
  for (const double share : {0.1, 0.45, 0.8, 0.999}) {
    const auto most = static_cast<std::size_t>(share * static_cast<double>(total));
    const Zigzag side_by_side(true), in_turn(true);
    const std::string a = run(side_by_side, most, 32), b = run(in_turn, most, 1);
    EXPECT_EQ(a, b);
    EXPECT_NE(a.find("more than " + std::to_string(most) + " clip samples"), std::string::npos)
        << a;
    EXPECT_NE(a, last);  // a later line each time
    last = a;
    EXPECT_LT(side_by_side.looked, 2 * static_cast<long>(most));
  }
}

}  // namespace
}  // namespace nonplanar
