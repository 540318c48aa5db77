// LayerGaps (check.hpp): layer thickness where a layer's extrusions cross the ones under them.
//
// Notation: an upper line a → b and an earlier lower line p → q cross, seen from above, at
// a + u·(b − a) = p + v·(q − p) with u, v ∈ [0, 1]; the gap there is
// z_a + u·(z_b − z_a) − (z_p + v·(z_q − z_p)).
#include <algorithm>
#include <cmath>
#include <map>

#include "nonplanar/check.hpp"

namespace nonplanar {

namespace {

// Earlier material is looked for this far under a line, mm: a bead over a void deeper than
// this bridges it, and no thickness is measured there.
constexpr double kDepth = 1.0;
// Earlier layers kept: a shell's pieces come back to their layer below after a few of the
// core's (eight, on the rib beside a taller tower).
constexpr std::size_t kLayersKept = 24;
// Widest bead looked for beside a crossing, mm (a layer's bbox is widened by half of it).
constexpr double kWidest = 2.0;
// Most cells of a grid (and at most 512 along a side): a hostile file's layer of a million
// lines 2 km wide stays 6 MB.
constexpr double kMostCells = 1 << 18;
// Lines farther out than this are no print's (a broken file's), mm: left out, so a grid's
// arithmetic stays finite.
constexpr double kFarthest = 1e6;
// Side of the tiles a curved layer's lines are grouped in to find the layers under them, mm.
constexpr double kTile = 4.0;
// Lines of two layers, one over the other, differ in height by more than this, mm.
constexpr double kTier = 0.02;

// Lines laid across gaps by design, over or under which a crossing may be more than one layer
// apart: sparse infill over a lattice, bridges, support (PrusaSlicer's and OrcaSlicer's
// ;TYPE: names).
bool spans_gaps(std::string_view type) {
  return type == "Internal infill" || type.find("ridge") != std::string_view::npos ||
         type.find("upport") != std::string_view::npos;
}

// z of segment p → q at its point nearest to x, seen from above; false when that is farther
// than r from x.
bool z_near(const Vec3& p, const Vec3& q, const Vec2& x, double r, double* z) {
  const Vec2 d = (q - p).head<2>();
  const double dd = d.squaredNorm();
  const double s = dd > 0 ? std::clamp((x - p.head<2>()).dot(d) / dd, 0.0, 1.0) : 0.0;
  const Vec3 c = p + s * (q - p);
  if ((c.head<2>() - x).squaredNorm() > r * r) return false;
  *z = c.z();
  return true;
}

}  // namespace

// The lower layer's lines binned on a grid of square cells, each line in every cell it passes
// through (a column at a time: the line's y-range within the column), rows by cell.
class LayerGaps::LineGrid {
 public:
  /// The lines `ids` of `lines`, over their box.
  LineGrid(const std::vector<std::pair<Vec3, Vec3>>& lines, const std::vector<std::size_t>& ids) {
    for (std::size_t k : ids) {
      const auto& [a, b] = lines[k];
      lo_ = lo_.cwiseMin(a.head<2>().cwiseMin(b.head<2>()));
      hi_ = hi_.cwiseMax(a.head<2>().cwiseMax(b.head<2>()));
    }
    // Cells of 1 mm, coarser on a wide layer of few lines (a grid at most 4 cells per line).
    const Vec2 size = (hi_ - lo_).cwiseMax(Vec2(1e-3, 1e-3));
    const double area = size.x() * size.y();
    const double want = std::sqrt(area / (4.0 * static_cast<double>(ids.size())));
    // At most kMostCells cells (6 MB of counts and heights), however wide or long the layer.
    cell_ = std::max({1.0, want, std::sqrt(area / kMostCells), size.maxCoeff() / 512});
    nx_ = static_cast<int>(size.x() / cell_) + 1, ny_ = static_cast<int>(size.y() / cell_) + 1;
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (std::size_t k : ids)
      for_each_cell(lines[k].first, lines[k].second, [&](std::size_t c) { ++start_[c + 1]; });
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    std::vector<std::size_t> next(start_.begin(), start_.end() - 1);
    ids_.resize(start_.back());
    z_lo_.assign(start_.size() - 1, 1e300), z_hi_.assign(start_.size() - 1, -1e300);
    for (std::size_t k : ids) {
      const Vec3 &a = lines[k].first, &b = lines[k].second;
      for_each_cell(a, b, [&](std::size_t c) {
        ids_[next[c]++] = k;
        z_lo_[c] = std::min({z_lo_[c], a.z(), b.z()}),
        z_hi_[c] = std::max({z_hi_[c], a.z(), b.z()});
        z_bottom_ = std::min(z_bottom_, z_lo_[c]), z_top_ = std::max(z_top_, z_hi_[c]);
      });
    }
  }
  /// Whether some line reaches heights [lo, hi].
  bool meets(double lo, double hi) const { return z_top_ >= lo && z_bottom_ <= hi; }
  /// Whether some line in cell c reaches heights [lo, hi] (a curved layer spans millimetres;
  /// one cell of it, little).
  bool meets(std::size_t c, double lo, double hi) const { return z_hi_[c] >= lo && z_lo_[c] <= hi; }
  /// Whether a line in a cell meeting the box [lo, hi] reaches heights [z_lo, z_hi].
  bool meets_in(const Vec2& lo, const Vec2& hi, double z_lo, double z_hi) const {
    bool any = false;
    if (meets(z_lo, z_hi))
      for_each_cell_in(lo, hi, [&](std::size_t c) { any = any || meets(c, z_lo, z_hi); });
    return any;
  }
  /// The highest top of a cell a → b passes through among those with lines reaching into
  /// [lo, hi]; −∞ when there is none.
  double top_along(const Vec3& a, const Vec3& b, double lo, double hi) const {
    double top = -1e300;
    if (!meets(lo, hi)) return top;
    for_each_cell(a, b, [&](std::size_t c) {
      if (start_[c] < start_[c + 1] && meets(c, lo, hi)) top = std::max(top, z_hi_[c]);
    });
    return top;
  }
  /// f(cell, first, last) for every cell a → b passes through: the ids of lines there.
  template <class F>
  void for_each_cell(const Vec3& a, const Vec3& b, F&& f) const {
    // Lines elsewhere pass no cell (a long infill line beside a shell's few sloped lines).
    constexpr double e = 1e-6;  // a crossing computed on a line rounds off it
    if (std::max(a.x(), b.x()) < lo_.x() - e || std::min(a.x(), b.x()) > hi_.x() + e ||
        std::max(a.y(), b.y()) < lo_.y() - e || std::min(a.y(), b.y()) > hi_.y() + e)
      return;
    const double ax = (a.x() - lo_.x()) / cell_, bx = (b.x() - lo_.x()) / cell_;
    const double ay = (a.y() - lo_.y()) / cell_, by = (b.y() - lo_.y()) / cell_;
    const int i0 = clamp_x(std::floor(std::min(ax, bx))),
              i1 = clamp_x(std::floor(std::max(ax, bx)));
    for (int i = i0; i <= i1; ++i) {
      // The line's y at the column's two sides, clipped to the line.
      double y0 = ay, y1 = by;
      if (bx != ax) {
        const double s0 = std::clamp((i - ax) / (bx - ax), 0.0, 1.0);
        const double s1 = std::clamp((i + 1 - ax) / (bx - ax), 0.0, 1.0);
        y0 = ay + s0 * (by - ay), y1 = ay + s1 * (by - ay);
      }
      const int j0 = clamp_y(std::floor(std::min(y0, y1))),
                j1 = clamp_y(std::floor(std::max(y0, y1)));
      for (int j = j0; j <= j1; ++j) f(static_cast<std::size_t>(i) * ny_ + j);
    }
  }
  /// f(cell) for every cell that meets the box [lo, hi].
  template <class F>
  void for_each_cell_in(const Vec2& lo, const Vec2& hi, F&& f) const {
    if (hi.x() < lo_.x() || lo.x() > hi_.x() || hi.y() < lo_.y() || lo.y() > hi_.y()) return;
    const int i0 = clamp_x(std::floor((lo.x() - lo_.x()) / cell_));
    const int i1 = clamp_x(std::floor((hi.x() - lo_.x()) / cell_));
    const int j0 = clamp_y(std::floor((lo.y() - lo_.y()) / cell_));
    const int j1 = clamp_y(std::floor((hi.y() - lo_.y()) / cell_));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) f(static_cast<std::size_t>(i) * ny_ + j);
  }
  /// The cell that holds p (the nearest, past the grid's edge).
  std::size_t cell_of(const Vec2& p) const {
    return static_cast<std::size_t>(clamp_x(std::floor((p.x() - lo_.x()) / cell_))) * ny_ +
           clamp_y(std::floor((p.y() - lo_.y()) / cell_));
  }
  std::size_t first(std::size_t c) const { return start_[c]; }
  std::size_t last(std::size_t c) const { return start_[c + 1]; }
  std::size_t id(std::size_t k) const { return ids_[k]; }

 private:
  int clamp_x(double i) const { return static_cast<int>(std::clamp(i, 0.0, nx_ - 1.0)); }
  int clamp_y(double j) const { return static_cast<int>(std::clamp(j, 0.0, ny_ - 1.0)); }
  Vec2 lo_{1e300, 1e300}, hi_{-1e300, -1e300};
  double cell_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<std::size_t> start_, ids_;
  std::vector<double> z_lo_, z_hi_;  ///< per cell, of its lines
  double z_bottom_ = 1e300, z_top_ = -1e300;
};

struct LayerGaps::Layer {
  int index = -1;
  std::vector<std::pair<Vec3, Vec3>> lines;
  std::vector<double> width;  ///< each line's bead width (;WIDTH:), mm
  std::vector<char> spans;    ///< spans_gaps(its ;TYPE:)
  double widest = 0;
  double z_lo = 1e300, z_hi = -1e300;
  Vec2 lo{1e300, 1e300}, hi{-1e300, -1e300};
  /// The layer's plane: the height most of its level lines share (the file writes z to the
  /// µm, so they share it exactly). Lines level at it, and the others.
  double plane_z = -1e300;
  std::vector<std::size_t> planar, other;
  std::unique_ptr<LineGrid> planar_grid_, other_grid_;
  bool flat() const { return z_hi - z_lo < 1e-6; }
  /// Finds the plane and sorts the lines into planar and other.
  void split();
  /// The grid of the planar lines or of the others; null when there are none.
  const LineGrid* grid(bool of_planar) {
    const std::vector<std::size_t>& ids = of_planar ? planar : other;
    std::unique_ptr<LineGrid>& g = of_planar ? planar_grid_ : other_grid_;
    if (ids.empty()) return nullptr;
    if (!g) g = std::make_unique<LineGrid>(lines, ids);
    return g.get();
  }
  bool overlaps(const Layer& o, double margin) const {
    return lo.x() <= o.hi.x() + margin && o.lo.x() <= hi.x() + margin &&
           lo.y() <= o.hi.y() + margin && o.lo.y() <= hi.y() + margin;
  }
};

void LayerGaps::Layer::split() {
  if (flat()) {  // every line on the plane (no sort: a planar part's layers are all flat)
    plane_z = z_lo;
    planar.resize(lines.size());
    for (std::size_t k = 0; k < lines.size(); ++k) planar[k] = k;
    return;
  }
  std::vector<double> zs;
  for (const auto& [a, b] : lines)
    if (std::abs(a.z() - b.z()) < 1e-6) zs.push_back(a.z());
  std::sort(zs.begin(), zs.end());
  std::size_t best = 0;
  for (std::size_t i = 0, j = 0; i < zs.size(); i = j) {
    while (j < zs.size() && zs[j] - zs[i] < 1e-6) ++j;
    if (j - i > best) best = j - i, plane_z = zs[i];
  }
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const auto& [a, b] = lines[k];
    const bool on_plane = std::abs(a.z() - plane_z) < 1e-6 && std::abs(b.z() - plane_z) < 1e-6;
    (on_plane ? planar : other).push_back(k);
  }
}

LayerGaps::LayerGaps(std::function<bool(const CrossingGap&)> visit) : visit_(std::move(visit)) {}
LayerGaps::~LayerGaps() = default;

void LayerGaps::record(const CrossingGap& g) {
  if (crossings == 0 || g.gap < min) min = g.gap, min_at = g.at;
  if (!g.spans && g.gap > max) max = g.gap, max_at = g.at;
  ++crossings;
  if (visit_ && !visit_(g)) stopped_ = true;
}

void LayerGaps::add(const PrintMove& m) {
  if (stopped_ || !counted(m) || !(m.from.cwiseAbs().maxCoeff() <= kFarthest) ||
      !(m.to.cwiseAbs().maxCoeff() <= kFarthest))
    return;
  if (!current_ || current_->index != m.layer) {
    close_layer();
    current_ = std::make_unique<Layer>();
    current_->index = m.layer;
  }
  Layer& L = *current_;
  L.lines.emplace_back(m.from, m.to);
  L.width.push_back(std::clamp(m.width, 0.0, kWidest));
  L.widest = std::max(L.widest, L.width.back());
  L.spans.push_back(spans_gaps(m.type));
  L.z_lo = std::min({L.z_lo, m.from.z(), m.to.z()});
  L.z_hi = std::max({L.z_hi, m.from.z(), m.to.z()});
  L.lo = L.lo.cwiseMin(m.from.head<2>().cwiseMin(m.to.head<2>()));
  L.hi = L.hi.cwiseMax(m.from.head<2>().cwiseMax(m.to.head<2>()));
}

void LayerGaps::finish() {
  close_layer();
}

void LayerGaps::close_layer() {
  if (!current_) return;
  std::unique_ptr<Layer> up = std::move(current_);
  up->split();
  // The earlier layers that may lie under this one.
  std::vector<Layer*> under;
  bool all_flat = up->flat();
  for (const std::unique_ptr<Layer>& l : window_)
    if (l->overlaps(*up, 0.5 * kWidest) && l->z_hi > up->z_lo - kDepth && l->z_lo < up->z_hi) {
      under.push_back(l.get());
      all_flat = all_flat && l->flat();
    }
  // Flat on flat, the layer under it the one printed just before: planar slicing, the height
  // over that layer, unsearched. (A shell's flat pieces between a core's layers are searched:
  // boxes overlap where lines do not.)
  const Layer* highest = nullptr;
  for (const Layer* l : under)
    if (l->z_lo < up->z_lo - 1e-6 && (!highest || l->z_lo > highest->z_lo)) highest = l;
  if (!stopped_ && all_flat && highest && highest->index == up->index - 1) {
    record({up->z_lo - highest->z_lo, up->lines.front().first, false});
  } else if (!stopped_ && !under.empty()) {
    measure_crossings(*up, under);
  }
  window_.push_back(std::move(up));
  if (window_.size() > kLayersKept) window_.pop_front();
}

// A line off the plane is measured against the layer under it nearest below it there (the
// highest cell it passes), or the next when that one shows it no crossing on top: a chord of a
// curved layer lies over one layer (searched against every layer in reach, the bunny's
// 300 000 such lines took 20 million tests). The layers in reach are found per tile of the
// lines (a curved layer spans millimetres, a tile of it little).
void LayerGaps::measure_off_plane(const Layer& up, const std::vector<Layer*>& under) {
  std::map<std::pair<int, int>, std::vector<std::size_t>> tiles;
  for (std::size_t i : up.other) {
    const Vec2 m = 0.5 * (up.lines[i].first + up.lines[i].second).head<2>();
    tiles[{static_cast<int>(std::floor(m.x() / kTile)),
           static_cast<int>(std::floor(m.y() / kTile))}]
        .push_back(i);
  }
  std::vector<Layer*> reach;
  std::vector<std::pair<double, Layer*>> nearest;
  for (const auto& [key, ids] : tiles) {
    Vec2 lo(1e300, 1e300), hi(-1e300, -1e300);
    double z_lo = 1e300, z_hi = -1e300;
    for (std::size_t i : ids)
      for (const Vec3& v : {up.lines[i].first, up.lines[i].second})
        lo = lo.cwiseMin(v.head<2>()), hi = hi.cwiseMax(v.head<2>()), z_lo = std::min(z_lo, v.z()),
        z_hi = std::max(z_hi, v.z());
    reach.clear();
    for (Layer* dn : under)
      for (const bool of_planar : {true, false}) {
        const LineGrid* g = dn->grid(of_planar);
        if (g && g->meets_in(lo, hi, z_lo - kDepth, z_hi - kTier)) {
          reach.push_back(dn);
          break;
        }
      }
    for (std::size_t i : ids) {
      const auto& [a, b] = up.lines[i];
      const double lo_z = std::min(a.z(), b.z()) - kDepth, hi_z = std::max(a.z(), b.z()) - kTier;
      nearest.clear();
      for (Layer* dn : reach) {
        double top = -1e300;
        for (const bool of_planar : {true, false})
          if (const LineGrid* g = dn->grid(of_planar))
            top = std::max(top, g->top_along(a, b, lo_z, hi_z));
        if (top > -1e300) nearest.emplace_back(top, dn);
      }
      std::sort(nearest.begin(), nearest.end(),
                [](const auto& p, const auto& q) { return p.first > q.first; });
      for (const auto& [top, dn] : nearest) {
        bool found = false;
        for (const bool of_planar : {true, false})
          if (const LineGrid* g = dn->grid(of_planar))
            found = cross(up, i, *dn, *g, under, false) || found;
        if (found || stopped_) break;
      }
    }
  }
}

// Every crossing of a line off the layer's plane, and of a planar line over such lines of
// the layers under it, is measured. A layer's planar lines over another's are as far above
// them as the two planes are apart: that counts once, for the highest plane under this one
// that they cross on top (the layer before, under a curved band's planar part or a core's
// layers; a shell's flat pieces elsewhere are not under it), and no lower one is searched.
void LayerGaps::measure_crossings(const Layer& up, const std::vector<Layer*>& under) {
  measure_off_plane(up, under);
  for (std::size_t i : up.planar)
    for (Layer* dn : under)
      if (const LineGrid* g = dn->grid(false)) cross(up, i, *dn, *g, under, false);
  if (up.planar.empty()) return;
  std::vector<Layer*> by_plane = under;
  std::sort(by_plane.begin(), by_plane.end(),
            [](const Layer* p, const Layer* q) { return p->plane_z > q->plane_z; });
  for (Layer* dn : by_plane) {
    if (dn->plane_z >= up.plane_z - kTier) continue;
    if (dn->plane_z < up.plane_z - kDepth || stopped_) break;
    const LineGrid* g = dn->grid(true);
    if (!g) continue;
    bool found = false;
    for (std::size_t k = 0; k < up.planar.size() && !found; ++k)
      found = cross(up, up.planar[k], *dn, *g, under, true);
    if (found) break;
  }
}

// The crossings of up's line i with dn's lines in grid g that are on top, recorded; the first
// only when `first`. Returns whether one was.
bool LayerGaps::cross(const Layer& up, std::size_t i, const Layer& dn, const LineGrid& g,
                      const std::vector<Layer*>& under, bool first) {
  const Vec3 &a = up.lines[i].first, &b = up.lines[i].second;
  const Vec2 ab = (b - a).head<2>();
  const double z_lo = std::min(a.z(), b.z()), z_hi = std::max(a.z(), b.z());
  bool found = false;
  if (!g.meets(z_lo - kDepth, z_hi - kTier)) return false;
  g.for_each_cell(a, b, [&](std::size_t c) {
    if ((first && found) || stopped_ || !g.meets(c, z_lo - kDepth, z_hi - kTier)) return;
    for (std::size_t k = g.first(c); k < g.last(c) && !stopped_ && !(first && found); ++k) {
      const std::size_t id = g.id(k);
      const Vec3 &p = dn.lines[id].first, &q = dn.lines[id].second;
      if (std::max(p.z(), q.z()) < z_lo - kDepth || std::min(p.z(), q.z()) > z_hi - kTier) continue;
      const Vec2 pq = (q - p).head<2>(), ap = (p - a).head<2>();
      const double den = ab.x() * pq.y() - ab.y() * pq.x();
      // Parallel lines (a perimeter over its twin) meet nowhere in particular.
      if (!(std::abs(den) > 1e-9 * ab.norm() * pq.norm())) continue;
      const double u = (ap.x() * pq.y() - ap.y() * pq.x()) / den;
      const double v = (ap.x() * ab.y() - ap.y() * ab.x()) / den;
      if (u < 0 || u > 1 || v < 0 || v > 1) continue;
      // Once, in the cell that holds the crossing (a pair shares more than one).
      const Vec3 x = a + u * (b - a);
      const std::size_t home = g.cell_of(x.head<2>());
      const double z_dn = p.z() + v * (q.z() - p.z()), gap = x.z() - z_dn;
      // Within kTier the two are one layer side by side: a shell's layer printed in pieces
      // between a core's layers meets itself where the pieces join.
      if (home != c || gap <= kTier || gap > kDepth || !on_top(dn, under, x, z_dn)) continue;
      // The thickest counts between the layers printed one after the other, neither line laid
      // over a gap by design: lines that span, and a shell's pieces over a core's stairs,
      // cross lines further down.
      const bool next = dn.index == up.index - 1 && !up.spans[i] && !dn.spans[id];
      record({gap, x, !first, !next});
      found = true;
    }
  });
  return found;
}

// No other earlier layer's bead covers x (its centre line within half its width) between the
// lower line's height z_dn and the upper one's x.z(): the lower line is the top of the
// material under x. (On a slope a layer under the lower line may look higher beside it: then
// the crossing is skipped, never misread.)
bool LayerGaps::on_top(const Layer& dn, const std::vector<Layer*>& under, const Vec3& x,
                       double z_dn) {
  const Vec2 p = x.head<2>();
  for (Layer* l : under) {
    if (l == &dn || l->z_hi < z_dn + kTier || l->z_lo > x.z() - kTier) continue;
    const Vec2 r(0.5 * l->widest, 0.5 * l->widest);
    bool higher = false;
    for (const bool of_planar : {true, false}) {
      const LineGrid* grid = l->grid(of_planar);
      if (!grid || higher) continue;
      grid->for_each_cell_in(p - r, p + r, [&](std::size_t c) {
        if (!grid->meets(c, z_dn + kTier, x.z() - kTier)) return;
        for (std::size_t k = grid->first(c); k < grid->last(c) && !higher; ++k) {
          const std::size_t id = grid->id(k);
          const Vec3 &s = l->lines[id].first, &t = l->lines[id].second;
          double z = 0;
          higher = z_near(s, t, p, 0.5 * l->width[id], &z) && z > z_dn + kTier && z < x.z() - kTier;
        }
      });
    }
    if (higher) return false;
  }
  return true;
}

}  // namespace nonplanar
