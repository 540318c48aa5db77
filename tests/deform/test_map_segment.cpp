// map_segment (deform/map_segment.hpp): near h_min, a segment mapped onto a layer with a
// narrow dip off its middle (a faceted top's kink, as on the held-out dome) keeps within the
// tolerance of the layer everywhere, not only at its midpoint, and the tolerance tightens.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "deform/map_segment.hpp"

namespace nonplanar {
namespace {

// Layers t = ζ, each lowered by a V-shaped dip 0.2 mm wide and `depth` deep around x = 0.33:
// z(x, y, t) = t − depth·max(0, 1 − |x − 0.33| / 0.1). The layer under is h_planar lower
// everywhere, so every point's thickness is h_planar.
class DipField : public LayerField {
 public:
  explicit DipField(double depth) : depth_(depth) {}
  double dip(double x) const { return depth_ * std::max(0.0, 1 - std::abs(x - 0.33) / 0.1); }
  double T(double x, double, double z) const override { return z + dip(x); }
  double z_at(double x, double, double t) const override { return t - dip(x); }
  double zeta(double t) const override { return t; }
  double t_of_zeta(double zeta) const override { return zeta; }
  double thickness(double, double, double) const override { return 1; }
  bool planar_at(double, double) const override { return false; }

 private:
  double depth_;
};

// The farthest the mapped polyline of a → b strays from the layer, vertically, over 2001
// samples.
double worst_stray(const DipField& f, const MapBackParams& params, double h) {
  const Vec3 a(0, 0, 1), b(1, 0, 1);
  ExtrusionPath out;
  const Mapped ma = map_point(f, a, h), mb = map_point(f, b, h);
  out.points.push_back(ma.p);
  out.height.push_back(ma.height);
  map_segment(f, a, ma, b, mb, h, params, 0, out);
  double worst = 0;
  for (int i = 0; i <= 2000; ++i) {
    const double x = i / 2000.0;
    const auto k = std::upper_bound(out.points.begin(), out.points.end(), x,
                                    [](double v, const Vec3& p) { return v < p.x(); }) -
                   out.points.begin();
    const std::size_t hi =
        std::min<std::size_t>(std::max<std::ptrdiff_t>(k, 1), out.points.size() - 1);
    const Vec3 &p = out.points[hi - 1], &q = out.points[hi];
    const double z = p.z() + (q.z() - p.z()) * (x - p.x()) / (q.x() - p.x());
    worst = std::max(worst, std::abs(z - f.z_at(x, 0, 1)));
  }
  return worst;
}

TEST(MapSegment, ADipOffTheMiddleIsFollowedWithinTheTolerance) {
  const DipField f(0.02);
  MapBackParams params;            // tolerance 0.01
  params.min_layer_height = 0.18;  // 0.2 mm layers, within 0.05 mm of h_min: probed
  EXPECT_LE(worst_stray(f, params, 0.2), params.tolerance + 1e-12);
  // The midpoint alone sees no dip there (the chord misses it by its whole depth) ...
  params.probe_spacing = 0;
  EXPECT_NEAR(worst_stray(f, params, 0.2), 0.02, 1e-9);
  // ... and far over h_min the midpoint is all that is asked: the mapping's cost.
  params.probe_spacing = 0.25, params.min_layer_height = 0.1;
  EXPECT_NEAR(worst_stray(f, params, 0.2), 0.02, 1e-9);
}

TEST(MapSegment, NearHMinTheChordKeepsWithinHalfTheMargin) {
  const DipField f(0.004);
  MapBackParams params;
  EXPECT_GT(worst_stray(f, params, 0.2), 0.0039);  // 0.004 deep passes tolerance 0.01 ...
  params.min_layer_height = 0.196;                 // ... but not 0.002 over h_min
  EXPECT_LE(worst_stray(f, params, 0.2), 0.002);
  params.min_layer_height = 0.2;  // at h_min: the finest tolerance, 0.0005
  EXPECT_LE(worst_stray(f, params, 0.2), 0.0005);
}

}  // namespace
}  // namespace nonplanar
