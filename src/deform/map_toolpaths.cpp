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

namespace {

// Finest chord tolerance, mm: half the gate's thickness slack, so where a layer is h_min thick
// two consecutive layers' chords (one under its surface, the other over) cross at least
// h_min − slack apart.
constexpr double kFinestTolerance = 0.0005;
// Segments are probed off their middle where their layer is less than this over h_min, mm: a
// dip the midpoint misses (0.008 mm deep on the held-out dome) brings a layer's line closer to
// the one under it there. Elsewhere the midpoint test alone keeps the mapping's cost (probes
// everywhere doubled the sine roof's).
constexpr double kProbeMargin = 0.05;

// The chord's tolerance between two points whose layer is ha and hb thick: the params'
// tolerance, held to half the margin over h_min where the layer comes within two tolerances
// of it.
double chord_tolerance(const MapBackParams& p, double ha, double hb) {
  if (!(p.min_layer_height > 0)) return p.tolerance;
  const double margin = 0.5 * (std::min(ha, hb) - p.min_layer_height);
  return std::min(p.tolerance, std::max(kFinestTolerance, margin));
}

// How far the mapped point at fraction s of a → b strays from the chord ma → mb.
double stray(const LayerField& f, const Vec3& a, const Mapped& ma, const Vec3& b, const Mapped& mb,
             double h, double s, Mapped* at) {
  *at = map_point(f, a + (b - a) * s, h);
  return (at->p - (ma.p + (mb.p - ma.p) * s)).norm();
}

// The point of a ≤ 1 mm curved segment that strays farthest from its chord, when that is more
// than tol: probes at fractions i/n at most `spacing` apart (the midpoint's stray d_mid is
// known), then, when the worst comes within a quarter of tol and strays more than a smooth
// layer would, a golden-section search between its neighbours for the peak (a V-shaped dip of
// the faceted top bottoms out between probes).
// Returns the fraction (0: none) and the mapped point there.
double worst_point(const LayerField& f, const Vec3& a, const Mapped& ma, const Vec3& b,
                   const Mapped& mb, double h, double spacing, double tol, double d_mid,
                   Mapped* at) {
  const int n = std::max(2, static_cast<int>(std::ceil((b - a).norm() / spacing)));
  double worst = 0, s_worst = 0;
  Mapped q;
  for (int i = 1; i < n; ++i) {
    const double s = static_cast<double>(i) / n;
    const bool mid = 2 * i == n;  // within tol: never split at, only searched around
    const double d = mid ? d_mid : stray(f, a, ma, b, mb, h, s, &q);
    if (d > worst) worst = d, s_worst = s, *at = mid ? *at : q;
  }
  if (worst > tol) return s_worst;
  // A smooth layer's chord strays 3/4 as far at the quarters as at the middle: more than that
  // (by an eighth of tol) is a kink between probes, worth the search.
  if (worst < 0.25 * tol || worst <= 0.75 * d_mid + 0.125 * tol) return 0;
  // Golden section over [s_worst − 1/n, s_worst + 1/n], the worst probe inside.
  constexpr double kGold = 0.6180339887498949;
  double lo = s_worst - 1.0 / n, hi = s_worst + 1.0 / n;
  double s1 = hi - kGold * (hi - lo), s2 = lo + kGold * (hi - lo);
  Mapped q1, q2;
  double d1 = stray(f, a, ma, b, mb, h, s1, &q1), d2 = stray(f, a, ma, b, mb, h, s2, &q2);
  for (int k = 0; k < 8; ++k) {
    if (d1 > tol) return *at = q1, s1;
    if (d2 > tol) return *at = q2, s2;
    if (d1 >= d2) {
      hi = s2, s2 = s1, d2 = d1, q2 = q1;
      s1 = hi - kGold * (hi - lo), d1 = stray(f, a, ma, b, mb, h, s1, &q1);
    } else {
      lo = s1, s1 = s2, d1 = d2, q1 = q2;
      s2 = lo + kGold * (hi - lo), d2 = stray(f, a, ma, b, mb, h, s2, &q2);
    }
  }
  return 0;
}

}  // namespace

void map_segment(const LayerField& f, const Vec3& a, const Mapped& ma, const Vec3& b,
                 const Mapped& mb, double h, const MapBackParams& params, int depth,
                 ExtrusionPath& out) {
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
  const double tol = chord_tolerance(params, ma.height, mb.height);
  const bool splits = depth < 16 && len > 0.02;
  const double d_mid = (mm.p - 0.5 * (ma.p + mb.p)).norm();
  if (splits && ((curved && len > 1.0) || d_mid > tol)) {
    map_segment(f, a, ma, mid, mm, h, params, depth + 1, out);
    map_segment(f, mid, mm, b, mb, h, params, depth + 1, out);
    return;
  }
  // The midpoint alone misses a kink off the middle: on the held-out dome a layer's chord
  // passed 0.008 mm over a 0.25 mm wide dip of its surface, where the layer above had a
  // vertex, and the two crossed 0.094 mm apart against h_min 0.1 (the layer 0.106 thick).
  Mapped mw{};
  const bool near_h_min = params.min_layer_height > 0 &&
                          std::min(ma.height, mb.height) < params.min_layer_height + kProbeMargin;
  const double s = curved && splits && near_h_min && params.probe_spacing > 0
                       ? worst_point(f, a, ma, b, mb, h, params.probe_spacing, tol, d_mid, &mw)
                       : 0;
  if (s > 0) {
    const Vec3 w = a + (b - a) * s;
    map_segment(f, a, ma, w, mw, h, params, depth + 1, out);
    map_segment(f, w, mw, b, mb, h, params, depth + 1, out);
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
void order_top_skins(std::vector<ExtrusionPath>& ps, const Toolhead& head) {
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
      for (const Vec3& v : ps[k].points) sh.mean += v.z(), sh.box.extend(v);
      sh.box.width = ps[k].width;
      sh.mean /= static_cast<double>(ps[k].points.size());
      sh.first = ps[k].points.front().z(), sh.last = ps[k].points.back().z();
      h.push_back(sh);
    }
    const program::LowToHigh order = program::low_to_high(h, head);
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
        map_segment(field, p.points[k - 1], prev, p.points[k], cur, p.height[k], params, 0, q);
        prev = cur;
      }
      add_to_reach(q, M, &min_z);
      M.paths.push_back(std::move(q));
    }
    M.nonplanar = M.max_z - min_z > 1e-6;
    if (M.paths.empty()) M.max_z = L.z;
    // Top skins on a slope, low to high (program::low_to_high, DESIGN.md §3).
    if (M.nonplanar) order_top_skins(M.paths, params.passes.head);
  });
  if (stop) return Error{Status::cancelled, "cancelled"};
  return out;
}

}  // namespace nonplanar
