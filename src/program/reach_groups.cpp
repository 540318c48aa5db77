// reach_groups and order_reach_groups (reach_groups.hpp).
#include "program/reach_groups.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nonplanar::program {

std::vector<std::size_t> reach_groups(const std::vector<ReachBox>& s, const Toolhead& head) {
  const std::size_t n = s.size();
  std::vector<std::size_t> up(n);
  for (std::size_t i = 0; i < n; ++i) up[i] = i;
  if (n < 2) return up;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, width = 0;
  for (const ReachBox& b : s)
    lo = std::min(lo, b.lo.z()), hi = std::max(hi, b.hi.z()), width = std::max(width, b.width);
  const double near = head.reach_under(hi - lo) + width + 0.1;
  auto root = [&](std::size_t i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  };
  // A sweep along x: each box against those starting no farther right than its end + near.
  std::vector<std::size_t> by_x(n);
  for (std::size_t i = 0; i < n; ++i) by_x[i] = i;
  std::sort(by_x.begin(), by_x.end(), [&](std::size_t a, std::size_t b) {
    return s[a].lo.x() < s[b].lo.x() || (s[a].lo.x() == s[b].lo.x() && a < b);
  });
  for (std::size_t a = 0; a < n; ++a) {
    const ReachBox& A = s[by_x[a]];
    for (std::size_t b = a + 1; b < n && s[by_x[b]].lo.x() <= A.hi.x() + near; ++b) {
      const ReachBox& B = s[by_x[b]];
      if (B.lo.y() > A.hi.y() + near || A.lo.y() > B.hi.y() + near) continue;
      const std::size_t ra = root(by_x[a]), rb = root(by_x[b]);
      if (ra != rb) up[std::max(ra, rb)] = std::min(ra, rb);  // the root: the group's first
    }
  }
  for (std::size_t i = 0; i < n; ++i) up[i] = root(i);
  return up;
}

std::vector<std::size_t> order_reach_groups(const std::vector<ExtrusionPath>& paths,
                                            const Toolhead& head, Vec2 from) {
  std::vector<ReachBox> boxes(paths.size());
  for (std::size_t i = 0; i < paths.size(); ++i) {
    for (const Vec3& p : paths[i].points) boxes[i].extend(p);
    boxes[i].width = paths[i].width;
  }
  const std::vector<std::size_t> group = reach_groups(boxes, head);
  std::vector<std::vector<std::size_t>> members(paths.size());
  std::vector<std::size_t> firsts;  // the groups, by their first path
  for (std::size_t i = 0; i < paths.size(); ++i) {
    if (members[group[i]].empty()) firsts.push_back(group[i]);
    members[group[i]].push_back(i);
  }
  std::vector<std::size_t> order;
  order.reserve(paths.size());
  std::vector<char> done(paths.size(), 0);
  for (std::size_t left = firsts.size(); left > 0; --left) {
    std::size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t g : firsts) {
      if (done[g] || paths[g].points.empty()) continue;
      const double d = (paths[g].points.front().head<2>() - from).squaredNorm();
      if (d < best_d) best_d = d, best = g;
    }
    if (!std::isfinite(best_d))  // only groups of empty paths are left
      for (std::size_t g : firsts)
        if (!done[g]) best = g;
    done[best] = 1;
    for (std::size_t i : members[best]) {
      order.push_back(i);
      if (!paths[i].points.empty()) from = paths[i].points.back().head<2>();
    }
  }
  return order;
}

}  // namespace nonplanar::program
