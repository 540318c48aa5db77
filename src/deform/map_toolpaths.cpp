// Inverse of the normalisation for toolpaths (DESIGN.md §2 step 6); notation in
// map_segment.hpp.
#include <algorithm>
#include <atomic>
#include <cmath>

#include "core/parallel.hpp"
#include "deform/map_segment.hpp"
#include "nonplanar/deform.hpp"
#include "program/layer_passes.hpp"

namespace nonplanar {

Mapped map_point(const LayerField& f, const Vec3& q, double h_planar) {
  if (f.planar_at(q.x(), q.y())) return {q, h_planar};
  const double t[2] = {f.t_of_zeta(q.z()), f.t_of_zeta(q.z() - h_planar)};
  double z[2];
  f.z_at(q.x(), q.y(), t, z, 2);
  return {{q.x(), q.y(), z[0]}, z[0] - z[1]};
}

void map_segment(const LayerField& f, const Vec3& a, const Mapped& ma, const Vec3& b,
                 const Mapped& mb, double h, double tol, int depth, ExtrusionPath& out) {
  const Vec3 mid = 0.5 * (a + b);
  const Mapped mm = map_point(f, mid, h);
  // A midpoint on the chord proves nothing over a long segment (a symmetric wave passes the
  // test): in curved regions segments are first cut to at most 1 mm. A segment is curved
  // when it crosses a band anywhere, not only at its ends and middle (a 110 mm infill line
  // on the bunny crossed a blend zone unmapped, 0.01 mm above the layer under it).
  const double len = (b - a).norm();
  const bool curved =
      mm.p.z() != mid.z() || ma.p.z() != a.z() || mb.p.z() != b.z() ||
      !f.planar_along(a.head<2>(), b.head<2>(), f.t_of_zeta(a.z() - h), f.t_of_zeta(a.z()));
  if (depth < 16 && len > 0.02 &&
      ((curved && len > 1.0) || (mm.p - 0.5 * (ma.p + mb.p)).norm() > tol)) {
    map_segment(f, a, ma, mid, mm, h, tol, depth + 1, out);
    map_segment(f, mid, mm, b, mb, h, tol, depth + 1, out);
    return;
  }
  out.points.push_back(mb.p);
  out.height.push_back(mb.height);
}

void add_to_reach(const ExtrusionPath& p, LayerToolpaths& L, double* min_z) {
  for (std::size_t k = 0; k < p.points.size(); ++k) {
    const Vec3& v = p.points[k];
    L.max_z = std::max(L.max_z, v.z());
    if (min_z) *min_z = std::min(*min_z, v.z());
    if (k == 0) continue;
    const double dxy = (v - p.points[k - 1]).head<2>().norm();
    if (dxy > 1e-3)
      L.max_slope = std::max(L.max_slope, std::abs(v.z() - p.points[k - 1].z()) / dxy);
  }
}

namespace {

bool is_top(const ExtrusionPath& p) {
  return p.role == ExtrusionRole::top_solid_infill;
}

// Each run of top-skin paths, in the order and direction the rule gives.
void order_top_skins(std::vector<ExtrusionPath>& ps) {
  for (std::size_t s = 0; s < ps.size();) {
    if (!is_top(ps[s])) {
      ++s;
      continue;
    }
    std::size_t e = s;
    while (e < ps.size() && is_top(ps[e])) ++e;
    std::vector<program::StrokeHeights> h;
    for (std::size_t k = s; k < e; ++k) {
      program::StrokeHeights sh;
      for (const Vec3& v : ps[k].points) sh.mean += v.z();
      sh.mean /= static_cast<double>(ps[k].points.size());
      sh.first = ps[k].points.front().z(), sh.last = ps[k].points.back().z();
      h.push_back(sh);
    }
    const program::LowToHigh order = program::low_to_high(h);
    std::vector<ExtrusionPath> run;
    for (std::size_t k : order.order) {
      run.push_back(std::move(ps[s + k]));
      if (order.reverse[k]) {
        std::reverse(run.back().points.begin(), run.back().points.end());
        std::reverse(run.back().height.begin(), run.back().height.end());
      }
    }
    std::move(run.begin(), run.end(), ps.begin() + static_cast<long>(s));
    s = e;
  }
}

}  // namespace

Expected<std::vector<LayerToolpaths>> map_toolpaths_back(const std::vector<LayerToolpaths>& planar,
                                                         const LayerField& field,
                                                         const MapBackParams& params,
                                                         const Context& ctx) {
  if (!(params.tolerance > 0)) return Error{Status::invalid_argument, "map tolerance: must be > 0"};
  std::vector<LayerToolpaths> out(planar.size());
  std::atomic<bool> stop{false};
  core::parallel_for(std::size_t{0}, planar.size(), [&](std::size_t li) {
    if (stop || ctx.cancelled()) return stop = true, void();
    const LayerToolpaths& L = planar[li];
    LayerToolpaths& M = out[li];
    M.z = L.z;
    M.height = L.height;
    M.max_z = -1e300;
    double min_z = 1e300;
    for (const ExtrusionPath& p : L.paths) {
      ExtrusionPath q;
      q.role = p.role, q.width = p.width, q.speed = p.speed;
      if (p.points.empty()) continue;
      Mapped prev = map_point(field, p.points[0], p.height[0]);
      q.points.push_back(prev.p);
      q.height.push_back(prev.height);
      for (std::size_t k = 1; k < p.points.size(); ++k) {
        const Mapped cur = map_point(field, p.points[k], p.height[k]);
        map_segment(field, p.points[k - 1], prev, p.points[k], cur, p.height[k], params.tolerance,
                    0, q);
        prev = cur;
      }
      add_to_reach(q, M, &min_z);
      M.paths.push_back(std::move(q));
    }
    M.nonplanar = M.max_z - min_z > 1e-6;
    if (M.paths.empty()) M.max_z = L.z;
    // Top skins on a slope, low to high (program::low_to_high, DESIGN.md §3).
    if (M.nonplanar) order_top_skins(M.paths);
  });
  if (stop) return Error{Status::cancelled, "cancelled"};
  return out;
}

}  // namespace nonplanar
