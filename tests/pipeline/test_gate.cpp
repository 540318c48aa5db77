// The safety gate (pipeline/gate.hpp) on a program without bands, where it looks for
// collisions only at the heights printed out of order (gate_zones.hpp's out_of_order).
#include <gtest/gtest.h>

#include <string>

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
  EXPECT_GT(none.lo, none.hi);
  EXPECT_EQ(none.last_layer, -1);
  // The core layer at 0.6 mm comes after the ramp's 4.6 mm: it alone is out of order, and the
  // layers above 4.6 mm are not.
  const OutOfOrder late = out_of_order(ramp_then_core(115));
  EXPECT_DOUBLE_EQ(late.lo, 0.6);
  EXPECT_DOUBLE_EQ(late.hi, 0.6);
  EXPECT_EQ(late.last_layer, 3);
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
  EXPECT_EQ(what, "an extrusion would hit earlier layers");
  what.clear();
  EXPECT_TRUE(run(160, &what)) << what;  // 40 mm away, beyond the heater block
}

}  // namespace
}  // namespace nonplanar
