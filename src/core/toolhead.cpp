// The head's allowance a(d) (notation in toolhead.hpp): the cone's wall below clearance(),
// the lowest slice whose polygons cover d above it.
#include "nonplanar/toolhead.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace nonplanar {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Inside (or on) a convex polygon of either winding.
bool inside_convex(const std::vector<Vec2>& poly, const Vec2& p) {
  if (poly.size() < 3) return false;
  int sign = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % poly.size()];
    const double c = (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
    if (c == 0) continue;
    const int s = c > 0 ? 1 : -1;
    if (sign != 0 && s != sign) return false;
    sign = s;
  }
  return true;
}

// Does the polygon's bounding box meet the box [lo, hi]? (A lower bound may say yes too often.)
bool box_meets(const std::vector<Vec2>& poly, const Vec2& lo, const Vec2& hi) {
  if (poly.size() < 3) return false;
  Vec2 plo = poly[0], phi = poly[0];
  for (const Vec2& v : poly) plo = plo.cwiseMin(v), phi = phi.cwiseMax(v);
  return plo.x() <= hi.x() && phi.x() >= lo.x() && plo.y() <= hi.y() && phi.y() >= lo.y();
}

double tan_deg(double deg) {
  return std::tan(deg * M_PI / 180.0);
}

// Farthest offset of a shaped head: the cone up to `cone_height`, and every slice's corners.
double shape_reach(const Toolhead& h, double cone_height) {
  double r = h.tip_radius + cone_height / tan_deg(h.cone_angle_deg);
  for (const ToolheadSlice& s : h.shape)
    for (const auto& poly : s.polygons)
      for (const Vec2& v : poly) r = std::max(r, v.norm());
  return r;
}

}  // namespace

double Toolhead::cone_top() const {
  if (shape.empty()) return block_clearance;
  // The lowest slice over the nozzle; a head with nothing over it (odd, but valid) keeps its
  // cone up to the highest slice.
  double over = kInf, highest = 0;
  for (const ToolheadSlice& s : shape) {
    highest = std::max(highest, s.height);
    for (const auto& poly : s.polygons)
      if (inside_convex(poly, Vec2(0, 0))) over = std::min(over, s.height);
  }
  return std::isfinite(over) ? over : highest;
}

double Toolhead::reach() const {
  return shape.empty() ? block_radius : shape_reach(*this, cone_top());
}

double Toolhead::reach_under(double height) const {
  const double h = std::max(0.0, height);
  if (shape.empty())
    return h > block_clearance
               ? std::max(block_radius, tip_radius + block_clearance / tan_deg(cone_angle_deg))
               : tip_radius + h / tan_deg(cone_angle_deg);
  Toolhead under = *this;
  std::erase_if(under.shape, [&](const ToolheadSlice& s) { return s.height >= h; });
  return shape_reach(under, std::min(cone_top(), h));
}

double Toolhead::clearance() const {
  if (shape.empty()) return block_clearance;
  double h = kInf;
  for (const ToolheadSlice& s : shape)
    if (!s.polygons.empty()) h = std::min(h, s.height);
  return h;
}

std::string Toolhead::describe() const {
  char buf[200];
  if (shape.empty())
    std::snprintf(buf, sizeof buf,
                  "round (tip %.2f mm, cone %.1f deg, block r %.1f mm from %.1f mm)", tip_radius,
                  cone_angle_deg, block_radius, block_clearance);
  else
    std::snprintf(buf, sizeof buf,
                  "%s (tip %.2f mm, cone %.1f deg, %zu slices from %.1f mm, "
                  "reach %.0f mm)",
                  shape_name.empty() ? "shape" : shape_name.c_str(), tip_radius, cone_angle_deg,
                  shape.size(), clearance(), reach());
  return buf;
}

HeadClearance::HeadClearance(const Toolhead& head, double tallest)
    : head_(head),
      shaped_(!head.shape.empty()),
      tan_cone_(tan_deg(head.cone_angle_deg)),
      cone_top_(head.cone_top()),
      reach_(head.reach()) {
  if (!shaped_) return;
  // A slice at or above `tallest` never holds a(d) below what material can reach.
  std::erase_if(head_.shape, [&](const ToolheadSlice& s) { return s.height >= tallest; });
  reach_ = head.reach_under(tallest);
}

// `nearest`: the offset nearest the axis (of the box, or d itself); with in_box, slices count
// where their polygons' bounding boxes meet [lo, hi], else where a polygon holds `nearest`.
double HeadClearance::at(const Vec2& nearest, bool in_box, const Vec2& lo, const Vec2& hi,
                         bool cone_too) const {
  const double r = nearest.norm();
  const double cone = cone_too ? std::max(0.0, r - head_.tip_radius) * tan_cone_ : kInf;
  if (!shaped_) return r <= head_.block_radius ? std::min(cone, cone_top_) : kInf;
  double a = cone < cone_top_ ? cone : kInf;
  for (const ToolheadSlice& s : head_.shape)
    if (s.height < a)
      for (const auto& poly : s.polygons)
        if (in_box ? box_meets(poly, lo, hi) : inside_convex(poly, nearest)) {
          a = s.height;
          break;
        }
  return a;
}

double HeadClearance::allowance(const Vec2& d) const {
  return at(d, false, d, d, true);
}

double HeadClearance::block_allowance(const Vec2& d) const {
  return at(d, false, d, d, false);
}

double HeadClearance::allowance_lower_bound(const Vec2& lo, const Vec2& hi) const {
  return at(Vec2(0, 0).cwiseMax(lo).cwiseMin(hi), true, lo, hi, true);
}

double travel_height(const Vec3& from, const Vec3& to, double layer_top, double slope,
                     double tip_radius, double lift) {
  const double d = (to.head<2>() - from.head<2>()).norm();
  const bool far = d > 0.6 || std::abs(to.z() - from.z()) > 0.1;
  const double hop = slope * (0.5 * d + tip_radius);
  if (far) return std::max({layer_top, from.z(), to.z()}) + lift;
  if (hop > 0.05) return std::max(from.z(), to.z()) + hop + 0.05;
  return std::numeric_limits<double>::quiet_NaN();
}

double travel_lift(double retract_lift) {
  return std::max(0.3, retract_lift);
}

}  // namespace nonplanar
