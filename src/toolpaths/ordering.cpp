#include <algorithm>

#include "toolpaths/toolpath_parts.hpp"

namespace nonplanar::paths {

void order_paths(std::vector<ExtrusionPath>& paths, Vec2 from) {
  std::vector<ExtrusionPath> out;
  out.reserve(paths.size());
  std::vector<char> used(paths.size(), 0);
  for (std::size_t n = 0; n < paths.size(); ++n) {
    double best = 1e300;
    std::size_t bi = 0, bj = 0;
    bool reverse = false;
    for (std::size_t i = 0; i < paths.size(); ++i) {
      if (used[i]) continue;
      const auto& pts = paths[i].points;
      const bool closed = pts.size() > 2 && pts.front() == pts.back();
      if (closed) {
        for (std::size_t j = 0; j + 1 < pts.size(); ++j) {
          const double d = (pts[j].head<2>() - from).squaredNorm();
          if (d < best) best = d, bi = i, bj = j, reverse = false;
        }
      } else {
        const double d0 = (pts.front().head<2>() - from).squaredNorm();
        const double d1 = (pts.back().head<2>() - from).squaredNorm();
        if (d0 < best) best = d0, bi = i, bj = 0, reverse = false;
        if (d1 < best) best = d1, bi = i, bj = 0, reverse = true;
      }
    }
    ExtrusionPath p = std::move(paths[bi]);
    used[bi] = 1;
    auto& pts = p.points;
    if (pts.size() > 2 && pts.front() == pts.back()) {
      pts.pop_back();
      std::rotate(pts.begin(), pts.begin() + static_cast<long>(bj), pts.end());
      pts.push_back(pts.front());
    } else if (reverse) {
      std::reverse(pts.begin(), pts.end());
    }
    from = pts.back().head<2>();
    out.push_back(std::move(p));
  }
  paths = std::move(out);
}

}  // namespace nonplanar::paths
