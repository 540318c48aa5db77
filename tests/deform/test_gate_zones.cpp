// The safety gate looks for collisions only near curved bands (deform/gate_zones.hpp). That
// must lose nothing: with a printer so tight that the curved layers collide a lot, the gate's
// count equals the full check's, while it reads far fewer moves.
#include <gtest/gtest.h>

#include <cmath>

#include "deform/gate_zones.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

TEST(GateZones, FindEveryCollisionTheFullCheckFinds) {
  // A 10 mm slab with a dome on its flat top: planar material beside the curved band at the
  // band's own height, so collisions also happen at planar points next to the band.
  auto top = [](double x, double y) {
    const double r2 = (x - 30) * (x - 30) + (y - 30) * (y - 30);
    return r2 < 144 ? 10 + 0.01 * (144 - r2) : 10.0;
  };
  TriangleMesh mesh = test::height_field_solid(top, 0, 60, 0, 60, 120, 120);
  for (Vec3& v : mesh.vertices) v += Vec3(80, 80, 0);
  const PrintConfig c;
  auto r = slice_model(mesh, make_job(c), {});
  ASSERT_TRUE(r) << r.error().message;
  ASSERT_EQ(r->plan.stacks.size(), 1u);
  const auto* field = dynamic_cast<const layers::BandedField*>(r->plan.field.get());
  ASSERT_NE(field, nullptr);

  // A heater block 0.3 mm above the tip and a 10° cone: the dome's layers now collide.
  CheckParams cp;
  cp.block_clearance = 0.3;
  cp.nozzle_angle_deg = 10;
  cp.collisions_only = true;
  const std::vector<PrintMove> all = moves_from_toolpaths(r->layers, c.gcode);
  auto full = check_print(all, nullptr, cp, {});
  ASSERT_TRUE(full);

  GateZones zones = gate_zones(*field, cp.block_radius);
  zones.find_last_layers(r->layers);
  ASSERT_EQ(zones.query.size(), 1u);
  const std::vector<PrintMove> near = moves_from_toolpaths(
      r->layers, c.gcode, [&](const ExtrusionPath& p, int li) { return zones.may_matter(p, li); });
  cp.collision_zones = zones.query;
  auto gated = check_print(near, nullptr, cp, {});
  ASSERT_TRUE(gated);

  EXPECT_GT(full->collisions, 100u);
  EXPECT_EQ(gated->collisions, full->collisions);
  EXPECT_EQ(gated->first_collision, full->first_collision);
  EXPECT_EQ(gated->collision_points.size(), full->collision_points.size());
  // The slab below the band is left out.
  EXPECT_LT(static_cast<double>(near.size()), 0.9 * static_cast<double>(all.size()));
}

}  // namespace
}  // namespace nonplanar
