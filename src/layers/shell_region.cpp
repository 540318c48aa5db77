// Notation as in shell_region.hpp.
#include "layers/shell_region.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/huge_pages.hpp"

namespace nonplanar::layers {
namespace {

constexpr double kAbove = 0.02;  ///< mm: the part stands above H by more than this
/// k: how fast the slack may grow with distance (mm/mm). The raster's bilinear slack can be
/// √2 k steep and the chamfer distance 8 % long, and the check's 0.2 mm cells read a point up to
/// 0.14 mm nearer: 0.12 keeps an inversion 0.54 mm off to 0.09 mm, under its h/2 (0.2 left 9
/// collisions on the rib; 0.15 left the bunny's shell one of 0.101 mm 0.40 mm off).
constexpr double kSlope = 0.12;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNarrowest = 0.7;  ///< mm: R narrower than this would print no line
constexpr int kMaxLevels = 8;       ///< heights g may print the shell at (shell_levels.hpp)

struct Raster {
  const FacetedTop& t;
  std::size_t index(int i, int j) const { return static_cast<std::size_t>(i) * t.ny + j; }
  Vec2 node(int i, int j) const { return t.origin + Vec2(i, j) * t.cell; }
  /// The nearest node to (x, y), clamped to the raster.
  std::size_t nearest(double x, double y) const {
    const int i =
        std::clamp(static_cast<int>(std::lround((x - t.origin.x()) / t.cell)), 0, t.nx - 1);
    const int j =
        std::clamp(static_cast<int>(std::lround((y - t.origin.y()) / t.cell)), 0, t.ny - 1);
    return index(i, j);
  }
  /// for_each_node_in (faceted_top.hpp) on this raster.
  template <class F>
  void covered(const Vec3& a, const Vec3& b, const Vec3& c, F&& f) const {
    for_each_node_in(t, a, b, c, std::forward<F>(f));
  }
};

// The nodes where the part stands above H: nodes inside a triangle (from above) whose plane is
// higher there, and the nearest node to any point of a triangle's edges (every half cell) that
// is, which catches walls and slivers that cover no node. `first` gets such a point. Faces
// marked in `kept_out` (may be empty) mark the nodes where they reach higher than H − kept_depth.
// So do both ends of a raster step where H is steeper than max_slope (dz/dx), and `steep` gets
// the first. Each mark says why (kAboveH first, then the first to mark).
enum Mark : char { kNone, kAboveH, kSteep, kKept, kNarrow, kFrame };
std::vector<char> stands_above(const TriangleMesh& mesh, const std::vector<char>& in_patch,
                               const std::vector<char>& kept_out, double kept_depth,
                               double max_slope, const Raster& r, Vec3* first, Vec3* steep) {
  const FacetedTop& H = r.t;
  std::vector<char> above(static_cast<std::size_t>(H.nx) * H.ny, 0);
  bool found = false, found_steep = false;
  auto mark = [&](std::size_t q, const Vec3& p, Mark why) {
    if (!above[q] || why == kAboveH) above[q] = why;
    if (!found) found = true, *first = p;
  };
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (in_patch[f]) continue;
    const auto& F = mesh.faces[f];
    const Vec3 v[3] = {mesh.vertices[F[0]], mesh.vertices[F[1]], mesh.vertices[F[2]]};
    const bool kept = !kept_out.empty() && kept_out[f];
    const double rise = kept ? -kept_depth : kAbove;
    auto why = [&](double z, double h) { return kept && z <= h + kAbove ? kKept : kAboveH; };
    r.covered(v[0], v[1], v[2], [&](int i, int j, double z) {
      const std::size_t q = r.index(i, j);
      if (z > H.h[q] + rise) mark(q, Vec3(r.node(i, j).x(), r.node(i, j).y(), z), why(z, H.h[q]));
    });
    for (int k = 0; k < 3; ++k) {
      const Vec3 &A = v[k], &B = v[(k + 1) % 3];
      const int n = 1 + static_cast<int>((B - A).head<2>().norm() / (0.5 * H.cell));
      for (int s = 0; s <= n; ++s) {
        const Vec3 q = A + (B - A) * (static_cast<double>(s) / n);
        const double h = H.height(q.x(), q.y());
        if (q.z() > h + rise) mark(r.nearest(q.x(), q.y()), q, why(q.z(), h));
      }
    }
  }
  // Where H itself is steeper than the nozzle may follow (overlapping shells in a mesh put
  // patch triangles of different heights over one spot: the CurviSlicer car's H rose 0.8 mm in
  // 0.4 mm), the core prints the part whole, as where it stands above.
  for (int i = 0; i < H.nx; ++i)
    for (int j = 0; j < H.ny; ++j)
      for (const auto& [di, dj] :
           {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}, std::pair{1, -1}}) {
        const int i2 = i + di, j2 = j + dj;
        if (i2 >= H.nx || j2 < 0 || j2 >= H.ny) continue;
        const std::size_t a = r.index(i, j), b = r.index(i2, j2);
        if (std::abs(H.h[a] - H.h[b]) <= max_slope * H.cell * std::hypot(di, dj)) continue;
        for (const std::size_t q : {a, b})
          if (!above[q]) above[q] = kSteep;
        if (!found_steep)
          found_steep = true, *steep = Vec3(r.node(i, j).x(), r.node(i, j).y(), H.h[a]);
      }
  if (!found && found_steep) *first = *steep;
  return above;
}

// t's raster with heights h (nx·ny), not a copy of t's own first.
FacetedTop with_heights(const FacetedTop& t, std::vector<double> h) {
  FacetedTop r;
  r.origin = t.origin, r.cell = t.cell, r.nx = t.nx, r.ny = t.ny, r.h_lo = t.h_lo, r.h_hi = t.h_hi;
  r.h = std::move(h);
  return r;
}

// Chamfer distance (mm) from every node to the nearest marked one, two passes with steps of
// one cell and a diagonal; +inf where nothing is marked. Each pass takes a row's three
// neighbours in the row before it first (independent of each other), then runs along the row
// (each node after the one before it); min is exact, so the order of the steps does not
// change a value.
std::vector<double> distance_to(const std::vector<char>& marked, const Raster& r) {
  const FacetedTop& t = r.t;
  const int nx = t.nx, ny = t.ny;
  std::vector<double> d = huge_vector(marked.size(), std::numeric_limits<double>::infinity());
  for (std::size_t q = 0; q < marked.size(); ++q)
    if (marked[q]) d[q] = 0;
  const double s = t.cell, sd = t.cell * M_SQRT2;
  // Row `to` from row `from` (its neighbour across), then along the row in direction dir.
  auto pass_row = [&](int to, int from, int dir) {
    double* row = &d[r.index(to, 0)];
    if (from >= 0 && from < nx) {
      const double* p = &d[r.index(from, 0)];
      for (int j = 0; j < ny; ++j) {
        double v = std::min(row[j], p[j] + s);
        if (j > 0) v = std::min(v, p[j - 1] + sd);
        if (j + 1 < ny) v = std::min(v, p[j + 1] + sd);
        row[j] = v;
      }
    }
    if (dir > 0)
      for (int j = 1; j < ny; ++j) row[j] = std::min(row[j], row[j - 1] + s);
    else
      for (int j = ny - 2; j >= 0; --j) row[j] = std::min(row[j], row[j + 1] + s);
  };
  for (int i = 0; i < nx; ++i) pass_row(i, i - 1, 1);
  for (int i = nx - 1; i >= 0; --i) pass_row(i, i + 1, -1);
  return d;
}

// out.slack and out.levels (notation in shell_region.hpp). s(d): the largest k-Lipschitz
// function under a(d) (a(d) at its lowest round the nozzle, a shaped head not being round;
// +inf past the head's reach), as a table by distance in cells, then + m. Lipschitz, so that
// shell points printed in order of their times never leave a higher point beside a later,
// lower one by more than k·d (min(k·d, a(d)) was not: next to the wall it rose as fast as the
// cone, and the gate found the rib's shell 0.12 mm over a later piece 0.27 mm away).
void set_slack(ShellRegion& out, std::vector<double> dist, const std::vector<char>& patch_node,
               const std::vector<char>& grown, const FacetedTop& top, double below,
               const LayerParams& p) {
  double farthest = 0;
  for (double d : dist)
    if (std::isfinite(d)) farthest = std::max(farthest, d);
  const HeadClearance head(p.toolhead);
  const std::size_t n = static_cast<std::size_t>(farthest / top.cell) + 2;
  std::vector<double> lip(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double d = static_cast<double>(i) * top.cell;
    double a = kInf;
    if (d <= head.reach())
      for (int k = 0; k < 16; ++k)
        a = std::min(a, head.allowance(d * Vec2(std::cos(k * M_PI / 8), std::sin(k * M_PI / 8))));
    lip[i] = a;
  }
  const double step = kSlope * top.cell;
  lip[0] = std::min(lip[0], 0.0);
  for (std::size_t i = 1; i < n; ++i) lip[i] = std::min(lip[i], lip[i - 1] + step);
  for (std::size_t i = n - 1; i-- > 0;) lip[i] = std::min(lip[i], lip[i + 1] + step);
  // m: the core printed before p rises at most s(p) = L(d) + m over it, d the distance to the
  // nodes outside R; its material lies at least d − √2·cell/2 from p (R's outline runs between
  // nodes), which the check may read 0.14 mm nearer (its 0.2 mm cells), where L is at most
  // k·(√2·cell/2 + 0.14) above the allowance there: m keeps that under h/2, with room for the
  // file's rounding. (h/4 was safe; the ornament's cap was then banded over 50.1 % of it.)
  const double m = 0.5 * p.layer_height - 0.005 - kSlope * (0.5 * M_SQRT2 * top.cell + 0.142);
  // In place of the distances: on the bunny's raster each is 16 MB, and two shells are
  // planned side by side.
  for (double& d : dist) {
    if (!std::isfinite(d)) {  // nothing stands above anywhere (not called then)
      d = 1e9;
      continue;
    }
    const double f = d / top.cell;
    const std::size_t i = std::min(static_cast<std::size_t>(f), n - 2);
    d = lip[i] + (lip[i + 1] - lip[i]) * (f - static_cast<double>(i)) + m;
  }
  out.slack = with_heights(top, std::move(dist));
  // g: the heights most patch nodes can be printed at (shell_levels.hpp), their intervals
  // [H − min(s, below), H + s].
  std::vector<double> u, lo, hi;
  for (std::size_t q = 0; q < out.slack.h.size(); ++q)
    if (patch_node[q] && !grown[q]) {
      u.push_back(top.h[q]);
      lo.push_back(top.h[q] - std::min(out.slack.h[q], below));
      hi.push_back(top.h[q] + out.slack.h[q]);
    }
  LevelChoice levels = choose_levels(u, lo, hi, kMaxLevels);
  out.levels = std::move(levels.levels);
  out.banded = levels.banded;
}

}  // namespace

ShellRegion shell_region(const TriangleMesh& mesh, const std::vector<char>& in_patch,
                         const std::vector<char>& kept_out, double kept_depth,
                         const FacetedTop& top, double below, const LayerParams& p, bool framed) {
  ShellRegion out;
  const Raster r{top};
  Vec3 first{0, 0, 0}, steep{0, 0, 0};
  std::vector<char> above =
      stands_above(mesh, in_patch, kept_out, kept_depth,
                   std::tan((p.max_angle_deg - 0.5) * M_PI / 180), r, &first, &steep);
  if (framed)  // past the raster the core prints all: its edge is as if the part stood above
    for (int i = 0; i < top.nx; ++i)
      for (int j = 0; j < top.ny; ++j)
        if ((i == 0 || j == 0 || i == top.nx - 1 || j == top.ny - 1) && !above[r.index(i, j)])
          above[r.index(i, j)] = kFrame;
  if (std::find_if(above.begin(), above.end(), [](char c) { return c != 0; }) == above.end())
    return out;  // R: everywhere
  // R shrinks by a node at its edge: the edges' points were marked at their nearest node only.
  std::vector<char> grown = above;
  for (int i = 0; i < top.nx; ++i)
    for (int j = 0; j < top.ny; ++j)
      if (above[r.index(i, j)])
        for (int di = -1; di <= 1; ++di)
          for (int dj = -1; dj <= 1; ++dj) {
            const int i2 = i + di, j2 = j + dj;
            if (i2 >= 0 && j2 >= 0 && i2 < top.nx && j2 < top.ny) grown[r.index(i2, j2)] = 1;
          }
  // R loses what is narrower than kNarrowest (an opening: what stays kNarrowest / 2 from its
  // edge, grown back by as much): the core is cut away under R, and where R is too small for
  // the shell to print a line (a lone node among steep ones on the saddle under a 15° cone) that
  // left a hole 9 mm deep in the top. What it loses counts as standing above.
  {
    const double half = 0.5 * kNarrowest;
    std::vector<char> core(grown.size(), 0);
    {  // gone before to_core is made: two of these are 16 MB each on the bunny's raster
      const std::vector<double> to_edge = distance_to(grown, r);
      for (std::size_t q = 0; q < grown.size(); ++q) core[q] = !grown[q] && to_edge[q] > half;
    }
    const std::vector<double> to_core = distance_to(core, r);
    for (std::size_t q = 0; q < grown.size(); ++q)
      if (!grown[q] && to_core[q] > half + 1e-9) grown[q] = 1, above[q] = kNarrow;
  }
  out.mask.origin = top.origin, out.mask.cell = top.cell, out.mask.nx = top.nx;
  out.mask.ny = top.ny;
  out.mask.in.resize(grown.size());
  for (std::size_t q = 0; q < grown.size(); ++q) out.mask.in[q] = grown[q] ? -1 : 1;

  // The patch's nodes: most of them must be in R.
  std::vector<char> patch_node(above.size(), 0);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    if (in_patch[f]) {
      const auto& F = mesh.faces[f];
      r.covered(mesh.vertices[F[0]], mesh.vertices[F[1]], mesh.vertices[F[2]],
                [&](int i, int j, double) { patch_node[r.index(i, j)] = 1; });
    }
  std::size_t on_patch = 0, in_r = 0, count[6] = {0, 0, 0, 0, 0, 0};
  for (std::size_t q = 0; q < above.size(); ++q)
    if (patch_node[q]) ++on_patch, in_r += !grown[q], ++count[static_cast<int>(above[q])];
  out.left_out = static_cast<double>(on_patch - in_r) * top.cell * top.cell;
  // Why, as the marks on the patch say (an overhang: the caller says where).
  if (count[kAboveH] > 0) out.why_out.push_back(notice_at("the part stands above it", first));
  if (count[kSteep] > 0) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "steeper than max_angle (%.1f deg) near (%.2f, %.2f)",
                  p.max_angle_deg, steep.x(), steep.y());
    out.why_out.push_back(buf);
  }
  if (count[kNarrow] > 0 && out.why_out.empty() && count[kKept] == 0)
    out.why_out.push_back("too narrow for the shell's lines between what the core prints");
  if (on_patch == 0 || 2 * in_r < on_patch) {
    out.refused = notice_at("the part stands above most of the curved top", first);
    return out;
  }
  // d: to the nodes outside R, where the core prints whole, not to the marks alone: R also
  // loses a ring round them and what is too narrow, 0.25 mm a node on the bunny's raster, and
  // the core there rose 0.105 mm over a shell point of the head 0.45 mm away (s was 0.105).
  set_slack(out, distance_to(grown, r), patch_node, grown, top, below, p);
  // Each band is printed apart, with its own travels and a seam: on the ankle base, banded
  // over 92 % of its heel, the shell took 402 printed layers and 1h33m against the planar
  // print's 85 and 32m (four curved layers then). With two the bands cost less: the ankle
  // base banded over 69 % took 50m against 47m for four unbanded, 78 % of its top within
  // 0.03 mm against 72 %; the ornament 2h41m against 2h39m, 70 % against 53 %. So bands are
  // allowed by default; shell_max_banded below 1 refuses a shell banded over more of it.
  out.stands_at = first.head<2>();
  if (out.banded > p.shell_max_banded)
    out.refused = banded_refusal(out.banded, out.stands_at, p.shell_max_banded);
  return out;
}

std::string banded_refusal(double banded, const Vec2& near, double limit) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the part stands above the curved top round %.0f %% of it, where the shell "
                "would follow it up in bands, each printed apart (near (%.2f, %.2f); "
                "shell_max_banded %.2f)",
                100 * banded, near.x(), near.y(), limit);
  return buf;
}

std::string notice_at(const char* what, const Vec3& p) {
  char buf[240];
  std::snprintf(buf, sizeof buf, "%s at (%.2f, %.2f, %.2f)", what, p.x(), p.y(), p.z());
  return buf;
}

}  // namespace nonplanar::layers
