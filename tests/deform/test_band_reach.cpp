// Where a curved band bends the layers (BandedField::reach), and the two stages that rely on
// it. The safety gate looks for collisions only near bands (pipeline/gate_zones.hpp): that must
// lose nothing, so with a printer so tight that the curved layers collide a lot, the gate's
// count equals the full check's while it reads far fewer moves. Mapping back splits a line
// wherever it crosses a band, even when its ends and middle are planar.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nonplanar/deform.hpp"
#include "nonplanar/pipeline.hpp"
#include "pipeline/gate.hpp"
#include "pipeline/gate_zones.hpp"
#include "support/solids.hpp"

namespace nonplanar {
namespace {

// A 10 mm slab with a dome on its flat top: planar material beside the curved band at the
// band's own height. Sliced with the default printer: one curved band.
struct DomeOnSlab {
  PrintConfig c;
  SliceResult r;
  const layers::BandedField* field = nullptr;
  DomeOnSlab() {
    auto top = [](double x, double y) {
      const double r2 = (x - 30) * (x - 30) + (y - 30) * (y - 30);
      return r2 < 144 ? 10 + 0.01 * (144 - r2) : 10.0;
    };
    TriangleMesh mesh = test::height_field_solid(top, 0, 60, 0, 60, 120, 120);
    for (Vec3& v : mesh.vertices) v += Vec3(80, 80, 0);
    auto s = slice_model(mesh, make_job(c), {});
    EXPECT_TRUE(s) << s.error().message;
    if (!s) return;
    r = std::move(*s);
    field = dynamic_cast<const layers::BandedField*>(r.plan.field.get());
  }
};

// The blend check's columns (BandedField::z_column: each root bracketed from the one below,
// to a given tolerance) against the field's own roots, through the dome's blend zone.
TEST(BandedField, AColumnsRootsAreTheFieldsWithinTheTolerance) {
  const DomeOnSlab d;
  ASSERT_NE(d.field, nullptr);
  ASSERT_EQ(d.field->bands().size(), 1u);
  const layers::Band& b = d.field->bands()[0];
  std::vector<double> t;
  for (int k = static_cast<int>(b.T_bottom); k <= static_cast<int>(b.T_bottom) + b.N + 10; ++k)
    t.push_back(k);
  int columns = 0;
  double worst = 0;
  for (int i = 0; i < b.blend_nx; i += 3)
    for (int j = 0; j < b.blend_ny; j += 3) {
      const double x = b.blend_origin.x() + i * b.blend_cell,
                   y = b.blend_origin.y() + j * b.blend_cell;
      const double beta = b.beta(x, y);
      if (beta <= 0.05 || beta >= 0.95) continue;
      ++columns;
      std::vector<double> z(t.size());
      d.field->z_column(x, y, t.data(), z.data(), static_cast<int>(t.size()), 1e-7);
      for (std::size_t k = 0; k < t.size(); ++k) {
        worst = std::max(worst, std::abs(z[k] - d.field->z_at(x, y, t[k])));
        if (k > 0) {
          EXPECT_GT(z[k], z[k - 1]);
        }
      }
    }
  EXPECT_GT(columns, 20);
  EXPECT_LE(worst, 1e-7);
}

// Two domes 22 mm apart over one slab: two bands whose blend zones overlap. Along the line
// between them a column's T has both bands' surfaces, fades and the first layer's kink; its
// boundaries (interpolated between T's pieces) are the field's roots, to well within the
// tolerance, and where a column has no stack of its own above c they fall between the
// planar ones.
TEST(BandedField, AColumnThroughTwoBandsHasTheFieldsRoots) {
  // Each dome on a mesa 4 mm over the slab: their walls split the top into two patches.
  auto top = [](double x, double y) {
    for (const double cx : {19.0, 41.0}) {
      const double r2 = (x - cx) * (x - cx) + (y - 30) * (y - 30);
      if (r2 < 100) return 14 + 0.02 * (100 - r2);
    }
    return 10.0;
  };
  TriangleMesh mesh = test::height_field_solid(top, 0, 60, 0, 60, 120, 120);
  for (Vec3& v : mesh.vertices) v += Vec3(80, 80, 0);
  PrintConfig c;
  auto r = slice_model(mesh, make_job(c), {});
  ASSERT_TRUE(r) << r.error().message;
  const auto* field = dynamic_cast<const layers::BandedField*>(r->plan.field.get());
  ASSERT_NE(field, nullptr);
  ASSERT_EQ(field->bands().size(), 2u);
  std::vector<double> t;
  for (double k = 0; k <= 100; k += 1) t.push_back(k);
  int both = 0;
  double worst = 0;
  for (double x = 80; x <= 140; x += 0.37) {
    const double y = 110.2;
    int reaching = 0;
    for (const layers::Band& b : field->bands()) reaching += b.beta(x, y) > 0;
    both += reaching == 2;
    std::vector<double> z(t.size());
    field->z_column(x, y, t.data(), z.data(), static_cast<int>(t.size()), 1e-7);
    for (std::size_t k = 0; k < t.size(); ++k) {
      worst = std::max(worst, std::abs(z[k] - field->z_at(x, y, t[k])));
      if (k > 0) {
        EXPECT_GT(z[k], z[k - 1]) << "x = " << x << ", t = " << t[k];
      }
    }
  }
  EXPECT_GT(both, 10);
  EXPECT_LE(worst, 1e-8);
}

TEST(GateZones, FindEveryCollisionTheFullCheckFinds) {
  const DomeOnSlab d;
  const SliceResult* r = &d.r;
  ASSERT_EQ(r->plan.stacks.size(), 1u);
  const layers::BandedField* field = d.field;
  ASSERT_NE(field, nullptr);

  // A heater block 0.3 mm above the tip and a 10° cone: the dome's layers now collide.
  CheckParams cp;
  cp.toolhead.block_clearance = 0.3;
  cp.toolhead.cone_angle_deg = 10;
  const auto all = read_gcode_moves(r->gcode);
  ASSERT_TRUE(all);
  auto full = find_collisions(*all, cp, nullptr, {});
  ASSERT_TRUE(full);

  GateZones zones = gate_zones(*field, cp.toolhead.reach());
  zones.find_last_layers(r->layers);
  ASSERT_EQ(zones.query.size(), 1u);
  // As the gate reads them: streamed from the text, only the moves the zones keep.
  std::size_t near = 0;
  const MoveReplay kept = [&](const std::function<void(const PrintMove&)>& f) {
    near = 0;
    for_each_print_move(
        r->gcode, [&](const GcodeMove& m) { return zones.may_matter(m, m.layer); },
        [&](const PrintMove& m) { ++near, f(m); });
  };
  auto in_zones = [&](const Vec3& p) {
    return std::any_of(zones.query.begin(), zones.query.end(),
                       [&](const BoundingBox& b) { return b.contains(p); });
  };
  auto gated = find_collisions(kept, cp, in_zones, {});
  ASSERT_TRUE(gated);

  EXPECT_GT(full->collisions, 100u);
  EXPECT_EQ(gated->collisions, full->collisions);
  EXPECT_EQ(gated->first_collision, full->first_collision);
  EXPECT_EQ(gated->points.size(), full->points.size());
  // The slab below the band is left out.
  EXPECT_LT(static_cast<double>(near), 0.9 * static_cast<double>(all->size()));
}

// A straight extrusion whose ends and middle lie where the layers are planar, but which
// crosses the band on its way, is mapped onto the curved layer all along (a 110 mm infill
// line on the bunny was left at its planar height over a blend zone, 0.01 mm above the
// layer under it).
TEST(MapToolpaths, ALongLineCrossingABandFollowsTheCurvedLayer) {
  const DomeOnSlab d;
  ASSERT_NE(d.field, nullptr);
  ASSERT_EQ(d.field->reach().size(), 1u);
  const layers::BandedField::Reach& box = d.field->reach()[0];
  const layers::Band& band = d.field->bands()[0];
  // Halfway up the band, from 5 mm left of its box to far enough right that the middle is
  // beyond the box too.
  const double t = band.T_bottom + 0.5 * band.N, zeta = d.field->zeta(t);
  const double y = 0.5 * (box.lo.y() + box.hi.y());
  const double x0 = box.lo.x() - 5, x1 = box.hi.x() + (box.hi.x() - box.lo.x()) + 10;
  ASSERT_FALSE(!d.field->planar_at(x0, y) || !d.field->planar_at(x1, y) ||
               !d.field->planar_at(0.5 * (x0 + x1), y));
  LayerToolpaths L;
  L.z = zeta;
  ExtrusionPath p;
  p.role = ExtrusionRole::internal_infill;
  p.points = {{x0, y, zeta}, {x1, y, zeta}};
  p.height = {0.2, 0.2};
  L.paths.push_back(p);
  auto mapped = map_toolpaths_back({L}, *d.field, {}, {});
  ASSERT_TRUE(mapped);
  const std::vector<Vec3>& q = (*mapped)[0].paths.at(0).points;
  // Everywhere along the mapped polyline, within the tolerance of the curved layer; and
  // the layer does leave the plane here.
  double worst = 0, bent = 0;
  for (std::size_t k = 1; k < q.size(); ++k)
    for (int s = 0; s <= 20; ++s) {
      const Vec3 v = q[k - 1] + (q[k] - q[k - 1]) * (s / 20.0);
      const double z = d.field->z_at(v.x(), v.y(), t);
      worst = std::max(worst, std::abs(v.z() - z));
      bent = std::max(bent, std::abs(z - zeta));
    }
  EXPECT_GT(bent, 0.1);
  EXPECT_LE(worst, MapBackParams{}.tolerance + 1e-6);
}
}  // namespace
}  // namespace nonplanar
