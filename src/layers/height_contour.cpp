// Marching squares. Notation: f = H − level at a node; a node is inside when f >= 0. A cell's
// corners c0 = (i, j), c1 = (i+1, j), c2 = (i+1, j+1), c3 = (i, j+1) run counter-clockwise and
// its edge e_k joins c_k to c_{k+1}. Walking the corners counter-clockwise, an edge goes from
// inside to outside (an exit) or back (an entry); a contour segment runs from an exit's
// crossing to an entry's, which keeps the inside on its left, so loops come out oriented.
#include "layers/height_contour.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "core/polygon_ops.hpp"

namespace nonplanar::layers {

ContourIndex::ContourIndex(const FacetedTop& H) : H_(H) {
  // Cells i = −1 … nx − 1 (and j alike); cell (i, j) is in block ((i + 1) / kBlock, …).
  bx_ = (H.nx + kBlock) / kBlock, by_ = (H.ny + kBlock) / kBlock;
  lo_.assign(static_cast<std::size_t>(bx_) * by_, std::numeric_limits<double>::infinity());
  hi_.assign(lo_.size(), -std::numeric_limits<double>::infinity());
  // A node belongs to the cells on both sides of it, so to up to four blocks.
  for (int i = -1; i <= H.nx; ++i)
    for (int j = -1; j <= H.ny; ++j) {
      const bool ring = i < 0 || j < 0 || i >= H.nx || j >= H.ny;
      const double v = ring ? -std::numeric_limits<double>::infinity()
                            : H.h[static_cast<std::size_t>(i) * H.ny + j];
      for (int ci = i - 1; ci <= i; ++ci)
        for (int cj = j - 1; cj <= j; ++cj) {
          if (ci < -1 || cj < -1 || ci > H.nx - 1 || cj > H.ny - 1) continue;
          const std::size_t b =
              static_cast<std::size_t>((ci + 1) / kBlock) * by_ + (cj + 1) / kBlock;
          lo_[b] = std::min(lo_[b], v);
          if (!ring) hi_[b] = std::max(hi_[b], v);
        }
    }
}

std::vector<ExPolygon> region_at_least(const FacetedTop& H, double level) {
  return ContourIndex(H).region_at_least(level);
}

std::vector<ExPolygon> ContourIndex::region_at_least(double level) const {
  const FacetedTop& H = H_;
  const int nx = H.nx, ny = H.ny;
  // Node values with a ring of outside nodes around the raster (indices −1 … n).
  auto f = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= nx || j >= ny) return -1.0;
    return H.h[static_cast<std::size_t>(i) * ny + j] - level;
  };
  auto node = [&](int i, int j) -> Vec2 {
    return Vec2(H.origin.x() + i * H.cell, H.origin.y() + j * H.cell);
  };
  // An edge is named by its lower-left node and its direction (0: +x, 1: +y).
  auto key = [&](int i, int j, int dir) {
    return (static_cast<std::uint64_t>(i + 1) * static_cast<std::uint64_t>(ny + 2) +
            static_cast<std::uint64_t>(j + 1)) *
               2 +
           static_cast<std::uint64_t>(dir);
  };
  auto crossing = [&](int i0, int j0, int i1, int j1) -> Vec2 {
    // Against the ring outside the raster the region ends at the raster's edge.
    auto outside = [&](int i, int j) { return i < 0 || j < 0 || i >= nx || j >= ny; };
    if (outside(i1, j1)) return node(i0, j0);
    if (outside(i0, j0)) return node(i1, j1);
    const double a = f(i0, j0), b = f(i1, j1);
    const double s = a / (a - b);
    return node(i0, j0) + s * (node(i1, j1) - node(i0, j0));
  };
  struct Seg {
    std::uint64_t to;
    Vec2 p;  ///< the start crossing's position
  };
  std::unordered_map<std::uint64_t, Seg> next;  // start edge → segment
  bool any = false;
  for (int blk = 0; blk < bx_ * by_; ++blk) {
    if (hi_[blk] < level) continue;  // every node below: no region, no contour
    if (lo_[blk] >= level) {         // every node above: region, no contour
      any = true;
      continue;
    }
    const int i0 = (blk / by_) * kBlock - 1, j0 = (blk % by_) * kBlock - 1;
    for (int i = i0; i < std::min(i0 + kBlock, nx); ++i)
      for (int j = j0; j < std::min(j0 + kBlock, ny); ++j) {
        const int ci[4] = {i, i + 1, i + 1, i}, cj[4] = {j, j, j + 1, j + 1};
        bool in[4];
        int n_in = 0;
        for (int k = 0; k < 4; ++k) n_in += in[k] = f(ci[k], cj[k]) >= 0;
        if (n_in == 0 || n_in == 4) {
          any |= n_in == 4;
          continue;
        }
        any = true;
        // Edge k as (key, crossing point); e0, e2 run along x, e1, e3 along y.
        auto edge_key = [&](int k) {
          const int a = k, b = (k + 1) % 4;
          return key(std::min(ci[a], ci[b]), std::min(cj[a], cj[b]), ci[a] != ci[b] ? 0 : 1);
        };
        int exits[2], entries[2], ne = 0, nn = 0;
        for (int k = 0; k < 4; ++k) {
          const int b = (k + 1) % 4;
          if (in[k] && !in[b]) exits[ne++] = k;
          if (!in[k] && in[b]) entries[nn++] = k;
        }
        const double mean =
            0.25 * (f(ci[0], cj[0]) + f(ci[1], cj[1]) + f(ci[2], cj[2]) + f(ci[3], cj[3]));
        for (int s = 0; s < ne; ++s) {
          const int e = exits[s];
          // The entry that closes this exit: the next one counter-clockwise, or (a saddle whose
          // centre is outside) the previous one.
          int pick = -1;
          for (int d = 1; d < 4 && pick < 0; ++d) {
            const int k = ne == 2 && mean < 0 ? (e + 4 - d) % 4 : (e + d) % 4;
            for (int t = 0; t < nn; ++t)
              if (entries[t] == k) pick = k;
          }
          const int a = e, b2 = (e + 1) % 4;
          next[edge_key(e)] = {edge_key(pick), crossing(ci[a], cj[a], ci[b2], cj[b2])};
        }
      }
  }
  if (!any) return {};
  std::vector<Polygon> loops;
  while (!next.empty()) {
    auto it = next.begin();
    const std::uint64_t start = it->first;
    Polygon loop;
    std::uint64_t k = start;
    while (true) {
      auto s = next.find(k);
      if (s == next.end()) break;  // cannot happen on a closed raster; keep what was found
      loop.push_back(s->second.p);
      k = s->second.to;
      next.erase(s);
      if (k == start) break;
    }
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return clip::union_loops(loops);
}

}  // namespace nonplanar::layers
