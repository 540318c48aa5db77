// Marching squares. Notation: f = H − level at a node; a node is inside when f >= 0. A cell's
// corners c0 = (i, j), c1 = (i+1, j), c2 = (i+1, j+1), c3 = (i, j+1) run counter-clockwise and
// its edge e_k joins c_k to c_{k+1}. Walking the corners counter-clockwise, an edge goes from
// inside to outside (an exit) or back (an entry); a contour segment runs from an exit's
// crossing to an entry's, which keeps the inside on its left, so loops come out oriented.
#include "layers/height_contour.hpp"

#include <cstdint>
#include <unordered_map>

#include "slice/polygon_ops.hpp"

namespace nonplanar::layers {

std::vector<ExPolygon> region_at_least(const FacetedTop& H, double level) {
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
  for (int i = -1; i < nx; ++i)
    for (int j = -1; j < ny; ++j) {
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
        const int a = e, b = (e + 1) % 4;
        next[edge_key(e)] = {edge_key(pick), crossing(ci[a], cj[a], ci[b], cj[b])};
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
