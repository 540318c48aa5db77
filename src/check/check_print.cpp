// The quality figures of DESIGN.md §4, from moves alone.
//
// Notation: an extrusion point is a sample along an extruding move (every ≤ 0.2 mm) with its
// layer; E_L(x, y) is layer L's extrusion height near (x, y), the least-squares plane
// through its points within 0.6 mm. Collision model (§3): nozzle tip radius r, wall angle α,
// block radius R and clearance H; earlier layers' material at q penetrates the nozzle at p by
// z(q) − z(p) − max(0, |q − p| − r)·tan α (cone) or z(q) − z(p) − H (block).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <tuple>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "core/column_caster.hpp"
#include "core/huge_pages.hpp"
#include "nonplanar/check.hpp"

namespace nonplanar {
namespace {

constexpr double kNear = 0.6;  // neighbourhood for plane fits, mm
// Least spread across the points for a plane fit (standard deviation), mm. Lines of one
// layer lie 0.45 mm apart; a sparse infill line with one point of another beside it spreads
// more than this but tilts a plane about the line (on the sphere's 30° rim that read a
// 0.22 mm layer as 0.30 mm), so plane_z also wants three points off the main line.
constexpr double kSpread = 0.1;

struct Pt {
  Vec3 p;
  int layer;
  bool sparse = false;  ///< sparse infill (";TYPE:Internal infill")
};

// Calls f on every extrusion point: every 0.2 mm along each counted move (the coverage test
// allows half of that beyond half a line width), in print order.
template <class F>
void for_each_sample(const std::vector<PrintMove>& moves, F&& f) {
  for (const PrintMove& m : moves) {
    if (!counted(m)) continue;
    const int n = std::max(1, static_cast<int>(std::ceil((m.to - m.from).norm() / 0.2)));
    const bool sparse = m.type == "Internal infill";
    for (int k = 1; k <= n; ++k)
      f(Pt{m.from + (m.to - m.from) * (static_cast<double>(k) / n), m.layer, sparse});
  }
}

// Extrusion points binned on an XY grid of kNear cells, dense over the points' box: the
// points of a cell are contiguous, in print order, so sorted by layer (layers only grow
// along a file), and each cell lists its runs of one layer for the plane fits, which read
// one layer. "The highest layer here" scans a cell's points from its end. (One list per cell
// made every plane fit walk all layers above that cell, quadratic in the part's height; a
// vector per (cell, layer) spent most of the time in the allocator; a hash map of (cell,
// layer) ranges spent 44 % of the bunny's check in its lookups and 2.4 GB with the sort's
// copies.)
class PointGrid {
 public:
  /// The samples of `moves` (for_each_sample), whose XY lie in [lo, hi].
  PointGrid(const std::vector<PrintMove>& moves, const Vec2& lo, const Vec2& hi) {
    if (lo.x() > hi.x()) return;
    // A cell more on every side: a sample at a move's end may round past the box.
    i0_ = cell(lo.x()) - 1, j0_ = cell(lo.y()) - 1;
    ni_ = cell(hi.x()) - i0_ + 2, nj_ = cell(hi.y()) - j0_ + 2;
    const auto cells = static_cast<std::size_t>(ni_ * nj_);
    // Counting sort by cell, in two passes over the samples: stable, so each cell keeps the
    // print order, and the points are held once.
    start_.assign(cells + 1, 0);
    for_each_sample(moves, [&](const Pt& q) { ++start_[index(cell(q.p.x()), cell(q.p.y())) + 1]; });
    for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    {
      std::vector<std::size_t> next(start_.begin(), start_.end() - 1);
      pts_.resize(start_[cells]);
      for_each_sample(moves,
                      [&](const Pt& q) { pts_[next[index(cell(q.p.x()), cell(q.p.y()))]++] = q; });
    }
    // Counted first, then made: grown by doubling, the bunny's 13 million runs peaked at
    // 400 MB of a 1.25 GB check.
    const auto starts_run = [&](std::size_t c, std::size_t k) {
      return k == start_[c] || pts_[k].layer != pts_[k - 1].layer;
    };
    std::size_t n = 0;
    for (std::size_t c = 0; c < cells; ++c)
      for (std::size_t k = start_[c]; k < start_[c + 1]; ++k) n += starts_run(c, k);
    runs_.reserve(n);
    first_run_.assign(cells + 1, 0);
    for (std::size_t c = 0; c < cells; ++c) {
      first_run_[c] = runs_.size();
      for (std::size_t k = start_[c]; k < start_[c + 1]; ++k)
        if (starts_run(c, k)) runs_.push_back({pts_[k].layer, static_cast<std::uint32_t>(k)});
    }
    first_run_[cells] = runs_.size();
  }
  const std::vector<Pt>& points() const { return pts_; }
  /// Calls f on every point of `layer` in the 3 x 3 cells around (x, y).
  template <class F>
  void near(double x, double y, int layer, F&& f) const {
    const long i = cell(x), j = cell(y);
    for (long a = i - 1; a <= i + 1; ++a)
      for (long b = j - 1; b <= j + 1; ++b) {
        if (!inside(a, b)) continue;
        const std::size_t c = index(a, b);
        const auto r0 = runs_.begin() + static_cast<std::ptrdiff_t>(first_run_[c]);
        const auto r1 = runs_.begin() + static_cast<std::ptrdiff_t>(first_run_[c + 1]);
        const auto r =
            std::lower_bound(r0, r1, layer, [](const Run& u, int l) { return u.layer < l; });
        if (r == r1 || r->layer != layer) continue;
        const std::size_t end = r + 1 == r1 ? start_[c + 1] : (r + 1)->begin;
        for (std::size_t k = r->begin; k < end; ++k) f(pts_[k]);
      }
  }
  /// The highest layer with a point within r (≤ kNear) of (x, y) and no higher than z_max,
  /// or -1.
  int top_layer(double x, double y, double r, double z_max) const {
    const long i = cell(x), j = cell(y);
    int top = -1;
    for (long a = i - 1; a <= i + 1; ++a)
      for (long b = j - 1; b <= j + 1; ++b) {
        if (!inside(a, b)) continue;
        const std::size_t c = index(a, b);
        // Sorted by layer within a cell: scan down from the top, stop at the best so far.
        for (std::size_t k = start_[c + 1]; k-- > start_[c] && pts_[k].layer > top;)
          if (pts_[k].p.z() <= z_max && (pts_[k].p.head<2>() - Vec2(x, y)).squaredNorm() <= r * r)
            top = pts_[k].layer;
      }
    return top;
  }

 private:
  static long cell(double x) { return static_cast<long>(std::floor(x / kNear)); }
  bool inside(long i, long j) const {
    return i >= i0_ && i < i0_ + ni_ && j >= j0_ && j < j0_ + nj_;
  }
  std::size_t index(long i, long j) const {
    return static_cast<std::size_t>((i - i0_) * nj_ + (j - j0_));
  }
  struct Run {
    int layer;
    std::uint32_t begin;  ///< its first point; it ends where the cell's next run begins
  };
  std::vector<Pt> pts_;
  long i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  std::vector<std::size_t> start_;      ///< per cell: its first point (and one past the last)
  std::vector<std::size_t> first_run_;  ///< per cell: its first run (and one past the last)
  std::vector<Run> runs_;
};

// z of the least-squares plane through points of `layer` within kNear of (x, y). Points
// along one line do not define a plane (a fit would extrapolate across it): then the
// nearest point's height is used.
// With `line`, the nearest point is returned there (when within 0.2 mm) and its height is
// not used: the caller handles a layer that is only a line here.
bool plane_z(const PointGrid& g, int layer, double x, double y, double* z, Vec3* line = nullptr,
             bool strict = false, Vec2* slope = nullptr) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int n = 0, sparse = 0;
  double nearest = 1e300, z_near = 0;
  Vec3 p_near(0, 0, 0);
  g.near(x, y, layer, [&](const Pt& q) {
    const double dx = q.p.x() - x, dy = q.p.y() - y, d2 = dx * dx + dy * dy;
    if (d2 > kNear * kNear) return;
    const Eigen::Vector3d r(1, dx, dy);
    A += r * r.transpose();
    b += r * q.p.z();
    if (d2 < nearest) nearest = d2, z_near = q.p.z(), p_near = q.p;
    ++n, sparse += q.sparse;
  });
  if (n == 0) return false;
  *z = z_near;
  if (line) *line = p_near;
  const bool close = nearest <= 0.2 * 0.2;
  if (n < 3) return !line && close;
  // Spread of the points in XY: the smallest eigenvalue of their covariance.
  const double mx = A(0, 1) / n, my = A(0, 2) / n;
  Eigen::Matrix2d cov;
  cov << A(1, 1) / n - mx * mx, A(1, 2) / n - mx * my, A(1, 2) / n - mx * my, A(2, 2) / n - my * my;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const double spread = strict ? kSpread : 0.5 * kSpread;
  if (eig.eigenvalues()[0] < spread * spread)
    return !line && close;  // a slope makes a farther point's height misleading
  if (strict) {
    // Sparse infill lines cross at angles and lie 2 mm or more apart: a plane through the
    // pieces within reach reads a sloped layer's height by their few points (0.34 mm for a
    // 0.29 mm layer on the bunny). Measure at the nearest line instead.
    if (2 * sparse > n) return !line && close;
    // One line and a stray point or two beside it spread enough, but tilt the plane about
    // the line: at least three points must lie off the points' main line (by 0.2 mm: the
    // stray point also tilts the principal axis, so the line's own ends sit up to 0.1 mm off
    // it). Thickness asks for this; the deviation keeps a tilted plane, which on a 27° slope
    // is still nearer the layer than the nearest point's height.
    const Vec2 across = eig.eigenvectors().col(0);
    int off = 0;
    g.near(x, y, layer, [&](const Pt& q) {
      const double dx = q.p.x() - x, dy = q.p.y() - y;
      if (dx * dx + dy * dy > kNear * kNear) return;
      off += std::abs((dx - mx) * across.x() + (dy - my) * across.y()) > 2 * kSpread;
    });
    if (off < 3) return !line && close;
  }
  const Eigen::Vector3d sol = A.ldlt().solve(b);
  *z = sol[0];
  if (slope) *slope = Vec2(sol[1], sol[2]);
  return true;
}

// Heights of deposited material per cell, split into "earlier layers" and "this layer",
// with maxima over blocks of 64, 16 and 4 cells a side to skip cells that cannot collide.
class Deposit {
 public:
  // The cells sit on a fixed lattice (multiples of 64 cells from the origin), so a check of
  // a subset of the moves (the slicer's gate) sees the same cells as a check of them all.
  Deposit(const Vec2& lo, const Vec2& hi, double cell)
      : lo_((lo / (kSize[0] * cell)).array().floor() * (kSize[0] * cell)), cell_(cell) {
    nx_ = static_cast<int>((hi.x() - lo_.x()) / cell) + 2;
    ny_ = static_cast<int>((hi.y() - lo_.y()) / cell) + 2;
    assign_huge(cells_, static_cast<std::size_t>(nx_) * ny_, Cell{});
    for (int l = 0; l < kLevels; ++l) {
      lx_[l] = nx_ / kSize[l] + 1, ly_[l] = ny_ / kSize[l] + 1;
      level_[l].assign(static_cast<std::size_t>(lx_[l]) * ly_[l], Cell{});
    }
  }
  void put(const Vec3& p, int layer) {
    const int i = ix(p.x()), j = iy(p.y());
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return;
    add(cells_[static_cast<std::size_t>(i) * ny_ + j], p.z(), layer);
    for (int l = 0; l < kLevels; ++l)
      add(level_[l][static_cast<std::size_t>(i / kSize[l]) * ly_[l] + j / kSize[l]], p.z(), layer);
    if (layer > top_layer_)
      top_earlier_ = std::max(top_earlier_, top_current_), top_current_ = -1e300,
      top_layer_ = layer;
    top_current_ = std::max(top_current_, p.z());
  }
  // Does earlier layers' material enter the nozzle at p deeper than `depth`? A block (64 × 64
  // cells, then 16 × 16, then 4 × 4) is skipped unless its highest point clears the smallest
  // allowance anywhere in it (the cone at the block's nearest distance, or the heater block).
  bool collides(const Vec3& p, int layer, const HeadClearance& head, double depth) const {
    // Nothing deposited reaches above p: no allowance can be negative, so no collision.
    // (Every layer printed above all earlier material, i.e. most of any part, stops here.)
    const double top = layer == top_layer_ ? top_earlier_ : std::max(top_earlier_, top_current_);
    if (top <= p.z() + depth) return false;
    const double R = head.reach();
    const Query q{
        p, layer, head, depth, ix(p.x() - R), ix(p.x() + R), iy(p.y() - R), iy(p.y() + R)};
    return search(q, 0, std::max(0, q.i0 / kSize[0]), std::min(lx_[0] - 1, q.i1 / kSize[0]),
                  std::max(0, q.j0 / kSize[0]), std::min(ly_[0] - 1, q.j1 / kSize[0]));
  }

 private:
  static constexpr int kLevels = 3;
  static constexpr int kSize[kLevels] = {64, 16, 4};  // cells per block side, coarse to fine
  struct Cell {
    double earlier = -1e300, current = -1e300;
    int layer = -1;
  };
  struct Query {
    const Vec3& p;
    int layer;
    const HeadClearance& head;
    double depth;
    int i0, i1, j0, j1;  ///< cell range within the block radius
  };
  static void add(Cell& c, double z, int layer) {
    if (c.layer < layer)
      c.earlier = std::max(c.earlier, c.current), c.current = -1e300, c.layer = layer;
    c.current = std::max(c.current, z);
  }
  // Only earlier layers count: a curved layer's own material beside p is higher than p all
  // along a slope, and would keep every block from being skipped.
  static double earlier_z(const Cell& c, int layer) {
    return c.layer < layer ? std::max(c.earlier, c.current) : c.earlier;
  }
  // Blocks [bi0, bi1] × [bj0, bj1] of level l (l = kLevels: cells).
  bool search(const Query& q, int l, int bi0, int bi1, int bj0, int bj1) const {
    const double R = q.head.reach();
    for (int bi = bi0; bi <= bi1; ++bi)
      for (int bj = bj0; bj <= bj1; ++bj) {
        if (l == kLevels) {
          const double z = earlier_z(cells_[static_cast<std::size_t>(bi) * ny_ + bj], q.layer);
          if (z <= q.p.z() + q.depth) continue;
          const double ex = lo_.x() + (bi + 0.5) * cell_ - q.p.x(),
                       ey = lo_.y() + (bj + 0.5) * cell_ - q.p.y();
          const double d2 = ex * ex + ey * ey;
          if (d2 > R * R) continue;
          if (z - q.p.z() - q.head.allowance(Vec2(ex, ey)) > q.depth) return true;
          continue;
        }
        const int n = kSize[l];
        const double bx0 = lo_.x() + bi * n * cell_, by0 = lo_.y() + bj * n * cell_;
        const double dx = std::max({bx0 - q.p.x(), 0.0, q.p.x() - (bx0 + n * cell_)});
        const double dy = std::max({by0 - q.p.y(), 0.0, q.p.y() - (by0 + n * cell_)});
        if (dx * dx + dy * dy > R * R) continue;
        // The head's allowance is never negative: a block no higher than p + depth is passed
        // before its (costlier) allowance is worked out.
        const double z = earlier_z(level_[l][static_cast<std::size_t>(bi) * ly_[l] + bj], q.layer);
        if (z <= q.p.z() + q.depth) continue;
        const double allow = q.head.allowance_lower_bound(
            Vec2(bx0 - q.p.x(), by0 - q.p.y()),
            Vec2(bx0 + n * cell_ - q.p.x(), by0 + n * cell_ - q.p.y()));
        if (z <= q.p.z() + q.depth + allow) continue;
        // The finer level's blocks (or the cells) inside this one, within the radius.
        const bool last = l + 1 == kLevels;
        const int sub = last ? 1 : kSize[l + 1];  // cells per child block
        const int f = n / sub;
        const int lo_i = bi * f, hi_i = bi * f + f - 1, lo_j = bj * f, hi_j = bj * f + f - 1;
        const int ci0 = q.i0 / sub, ci1 = q.i1 / sub, cj0 = q.j0 / sub, cj1 = q.j1 / sub;
        const int nxl = last ? nx_ : lx_[l + 1], nyl = last ? ny_ : ly_[l + 1];
        if (search(q, l + 1, std::max({lo_i, ci0, 0}), std::min({hi_i, ci1, nxl - 1}),
                   std::max({lo_j, cj0, 0}), std::min({hi_j, cj1, nyl - 1})))
          return true;
      }
    return false;
  }
  int ix(double x) const { return static_cast<int>(std::floor((x - lo_.x()) / cell_)); }
  int iy(double y) const { return static_cast<int>(std::floor((y - lo_.y()) / cell_)); }
  Vec2 lo_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  int lx_[kLevels] = {}, ly_[kLevels] = {};
  // Highest material of the layers before the newest one, and of the newest one.
  double top_earlier_ = -1e300, top_current_ = -1e300;
  int top_layer_ = -1;
  std::vector<Cell> cells_;
  std::vector<Cell> level_[kLevels];  ///< per block of each level, split like the cells
};

constexpr double kMaxSpan = 2000.0;  // mm: larger than any bed we know; 2.4 GB of grid at most

// What the extrusion points (for_each_sample) add up to.
struct Samples {
  Vec2 lo{1e300, 1e300}, hi{-1e300, -1e300};
  double filament = 0;
  std::size_t extrusions = 0;
  double steepest_deg = 0;
  double z_lo = 1e300, z_hi = -1e300;  // of every extrusion inside the print, the skirt's too
};

// Replays a vector of moves.
MoveReplay replay(const std::vector<PrintMove>& moves) {
  return [&moves](const std::function<void(const PrintMove&)>& f) {
    for (const PrintMove& m : moves) f(m);
  };
}

Expected<Samples> sample_extrusions(const MoveReplay& moves) {
  Samples s;
  std::optional<Error> error;
  moves([&](const PrintMove& m) {
    if (error || !m.extruding || m.layer < 0) return;
    s.z_lo = std::min({s.z_lo, m.from.z(), m.to.z()});
    s.z_hi = std::max({s.z_hi, m.from.z(), m.to.z()});
    if (!counted(m)) return;
    s.filament += m.filament;
    const double len = (m.to - m.from).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / 0.2)));
    s.lo = s.lo.cwiseMin(m.from.head<2>().cwiseMin(m.to.head<2>()));
    s.hi = s.hi.cwiseMax(m.from.head<2>().cwiseMax(m.to.head<2>()));
    // The grids below hold 0.2 mm cells over the extrusions' box: one move 10 m off once
    // asked for 6.8 GB. Checked before this move is sampled.
    if ((s.hi - s.lo).maxCoeff() > kMaxSpan) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "line %d: extrusions span %.0f x %.0f mm; check measures prints up to %.0f mm "
                    "across (a move far off the bed?)",
                    m.line, s.hi.x() - s.lo.x(), s.hi.y() - s.lo.y(), kMaxSpan);
      error = Error{Status::invalid_argument, buf};
      return;
    }
    s.extrusions += static_cast<std::size_t>(n);
    // The point grid numbers them in 32 bits (800 000 km of extrusion).
    if (s.extrusions > std::numeric_limits<std::uint32_t>::max()) {
      error = Error{Status::invalid_argument,
                    "line " + std::to_string(m.line) +
                        ": more extrusion than check measures (4 294 967 295 points 0.2 mm apart)"};
      return;
    }
    const double dxy = (m.to.head<2>() - m.from.head<2>()).norm();
    if (dxy > 0.05)
      s.steepest_deg =
          std::max(s.steepest_deg, std::atan2(std::abs(m.to.z() - m.from.z()), dxy) * 180 / M_PI);
  });
  if (error) return *error;
  return s;
}

constexpr double kTravelStep = 0.5;  ///< mm between the points of a travel looked at
constexpr double kUnderBed = 0.01;   ///< mm: a move lower than this under z = 0 hits the bed

// Collisions, in print order, among the points `looked_at` accepts (null: all).
Expected<CollisionFigures> search_collisions(const MoveReplay& moves, const Samples& s,
                                             const CheckParams& cp,
                                             const std::function<bool(const Vec3&)>& looked_at,
                                             const Context& ctx) {
  CollisionFigures f;
  // Material stands at most the print's height above the nozzle: higher parts of the head
  // (a gantry) are left out, which keeps the search radius that of the parts that can touch.
  const HeadClearance head(cp.toolhead, s.z_hi - s.z_lo);
  const double margin = head.reach() + 1;
  Deposit dep(s.lo - Vec2(margin, margin), s.hi + Vec2(margin, margin), 0.2);
  std::size_t mi = 0;
  bool cancelled = false;
  auto hit = [&](const Vec3& p, int line) {
    if (f.collisions == 0) f.first_collision = p, f.first_collision_line = line;
    // Spread out (1 mm apart at least): one long collision must not fill the list.
    if (f.points.size() < 4096 && (f.points.empty() || (f.points.back() - p).norm() > 1.0))
      f.points.push_back(p);
    ++f.collisions;
  };
  moves([&](const PrintMove& m) {
    if (cancelled || ((mi++ & 0xffff) == 0 && (cancelled = ctx.cancelled()))) return;
    if (m.layer < 0) return;
    const double len = (m.to - m.from).norm();
    // A travel goes where a head can: above the bed, and into no material printed before it
    // deeper than an extrusion may (the shell's first layer change, mapped where a core ended
    // on a support column, once sent the nozzle to z = -0.3 there). It lays none. A wipe
    // retraces the extrusion before it, on that extrusion's layer, though the slicer writes
    // it after the next layer change: only the bed is its business here.
    const double step = m.extruding ? 0.2 : kTravelStep;
    if (!m.extruding && len < 1e-9) return;
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int k = 1; k <= n; ++k) {
      const Vec3 p = m.from + (m.to - m.from) * (static_cast<double>(k) / n);
      if ((!m.extruding && p.z() < -kUnderBed) ||
          ((m.extruding || !m.wipe) && (!looked_at || looked_at(p)) &&
           dep.collides(p, m.layer, head, 0.5 * cp.layer_height)))
        hit(p, m.line);
      if (m.extruding) dep.put(p, m.layer);
    }
  });
  if (cancelled) return Error{Status::cancelled, "cancelled"};
  return f;
}

// Volume ratio and extrusion outside the mesh.
void measure_volume(const PointGrid& grid, const ColumnCaster& cols, const TriangleMesh& mesh,
                    double filament, const CheckParams& cp, CheckFigures& f) {
  f.volume_ratio = filament * M_PI * 0.25 * cp.filament_diameter * cp.filament_diameter /
                   std::max(signed_volume(mesh), 1e-12);
  const std::vector<Pt>& all = grid.points();
  std::size_t outside = 0, tested = 0;
  for (std::size_t k = 0; k < all.size(); k += 2) {
    ++tested;
    // The bead lies under the nozzle: test a quarter layer below the nozzle tip.
    if (!cols.inside(all[k].p.x(), all[k].p.y(), all[k].p.z() - 0.25 * cp.layer_height)) ++outside;
  }
  f.outside_fraction = tested ? static_cast<double>(outside) / static_cast<double>(tested) : 0.0;
}

// Top-surface deviation on printable up-facing facets between min_angle and max_angle. Samples
// are spread by area: a facet gets the largest lattice its area pays for (m(m + 1)/2 ≤
// density · area points); what is left over is carried from facet to facet, and a facet
// gets a sample at its centroid each time it adds up to one, so a fine mesh does not weigh its
// small facets more than a coarse one. A facet inside another body of the mesh (a box's top
// inside the dome set on it) is no surface and takes no samples.
void measure_deviation(const PointGrid& grid, const ColumnCaster& cols, const TriangleMesh& mesh,
                       const CheckParams& cp, CheckFigures& f) {
  std::vector<double> dev;
  const double cos_max = std::cos(cp.max_angle_deg * M_PI / 180.0);
  const double cos_min = std::cos(std::max(cp.min_angle_deg, 0.0) * M_PI / 180.0);
  const double density = cp.surface_samples_per_mm2;
  double carried = 0;  // what the facets so far left over, in samples
  auto sample = [&](const Vec3& s) {
    ++f.surface_samples;
    // The layer that prints this surface: the highest one whose extrusion covers this XY
    // within half a line width, ignoring material more than 1 mm above it (another part
    // of the model over this one, as an arch).
    const int top = grid.top_layer(s.x(), s.y(), 0.225 + 0.1, s.z() + 1.0);
    double z = 0;
    if (top < 0 || !plane_z(grid, top, s.x(), s.y(), &z)) return;
    ++f.covered_samples;
    const double d = std::abs(z - s.z());
    f.within_samples += d <= cp.within_tolerance;
    dev.push_back(d);
  };
  for (const auto& t : mesh.faces) {
    const Vec3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const Vec3 nrm = (b - a).cross(c - a);
    const double area = 0.5 * nrm.norm();
    if (!(area > 0)) continue;
    const double nz = nrm.z() / nrm.norm();
    if (nz <= cos_max || (cp.min_angle_deg > 0 && nz > cos_min)) continue;
    const Vec3 mid = (a + b + c) / 3.0;
    if (cols.inside(mid.x(), mid.y(), mid.z() + 0.05)) continue;
    const int m = static_cast<int>(std::floor((std::sqrt(8 * density * area + 1) - 1) / 2));
    carried += density * area - 0.5 * m * (m + 1);
    if (carried >= 1) carried -= 1, sample(mid);
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j)
        sample(a + (i + 1.0 / 3.0) / m * (b - a) + (j + 1.0 / 3.0) / m * (c - a));
  }
  if (f.surface_samples > 0)
    f.within_share = static_cast<double>(f.within_samples) / static_cast<double>(f.surface_samples);
  if (dev.empty()) return;
  std::sort(dev.begin(), dev.end());
  double sum = 0;
  for (double d : dev) sum += d;
  f.deviation_mean = sum / static_cast<double>(dev.size());
  f.deviation_p95 = dev[static_cast<std::size_t>(0.95 * static_cast<double>(dev.size() - 1))];
  f.deviation_max = dev.back();
}

}  // namespace

bool counted(const PrintMove& m) {
  return m.extruding && m.layer >= 0 && m.type != "Skirt/Brim";
}

CheckParams check_params(const PrintConfig& print, double max_angle_deg) {
  CheckParams cp;
  cp.max_angle_deg = max_angle_deg;
  cp.layer_height = print.slice.layer_height;
  cp.filament_diameter = print.gcode.filament_diameter;
  cp.toolhead = print.toolhead;
  return cp;
}

Expected<CollisionFigures> find_collisions(const std::vector<PrintMove>& moves,
                                           const CheckParams& params,
                                           const std::function<bool(const Vec3&)>& looked_at,
                                           const Context& ctx) {
  return find_collisions(replay(moves), params, looked_at, ctx);
}

Expected<CollisionFigures> find_collisions(const MoveReplay& moves, const CheckParams& params,
                                           const std::function<bool(const Vec3&)>& looked_at,
                                           const Context& ctx) {
  auto s = sample_extrusions(moves);
  if (!s) return s.error();
  if (s->extrusions == 0) return CollisionFigures{};
  auto f = search_collisions(moves, *s, params, looked_at, ctx);
  if (f) f->extrusions = s->extrusions, f->steepest_deg = s->steepest_deg;
  return f;
}

Expected<CheckFigures> check_print(const std::vector<PrintMove>& moves, const TriangleMesh* mesh,
                                   const CheckParams& cp, const Context& ctx) {
  CheckFigures f;
  auto s = sample_extrusions(replay(moves));
  if (!s) return s.error();
  f.extrusions = s->extrusions, f.steepest_deg = s->steepest_deg;
  if (f.extrusions == 0) return f;
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  LayerGaps gaps;
  for (const PrintMove& m : moves) gaps.add(m);
  gaps.finish();
  f.thickness_min = gaps.min, f.thickness_max = gaps.max;
  f.thickness_min_at = gaps.min_at, f.thickness_max_at = gaps.max_at;
  const PointGrid grid(moves, s->lo, s->hi);
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  ctx.progress("check", 0.3);
  auto c = search_collisions(replay(moves), *s, cp, nullptr, ctx);
  if (!c) return c.error();
  f.collisions = c->collisions, f.first_collision = c->first_collision;
  f.first_collision_line = c->first_collision_line, f.collision_points = std::move(c->points);
  ctx.progress("check", 0.6);
  if (!mesh) return f;
  if (ctx.cancelled()) return Error{Status::cancelled, "cancelled"};
  const ColumnCaster cols(*mesh);
  measure_volume(grid, cols, *mesh, s->filament, cp, f);
  measure_deviation(grid, cols, *mesh, cp, f);
  ctx.progress("check", 1.0);
  return f;
}

}  // namespace nonplanar
