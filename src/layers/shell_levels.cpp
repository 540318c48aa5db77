// Notation as in shell_levels.hpp.
#include "layers/shell_levels.hpp"

#include <algorithm>
#include <cmath>

namespace nonplanar::layers {

double ShellLevels::at(double u) const {
  if (z.empty()) return std::numeric_limits<double>::infinity();
  const double f = std::clamp(std::floor((u - u0) / bin), 0.0, static_cast<double>(last.back()));
  const auto it = std::lower_bound(last.begin(), last.end(), static_cast<int>(f));
  return z[static_cast<std::size_t>(it - last.begin())];
}

LevelChoice choose_levels(const std::vector<double>& u, const std::vector<double>& lo,
                          const std::vector<double>& hi, int max_levels) {
  LevelChoice out;
  const std::size_t n = u.size();
  if (n == 0 || max_levels < 1) return out;
  const auto [lo_it, hi_it] = std::minmax_element(u.begin(), u.end());
  const double u_min = *lo_it, range = *hi_it - u_min;
  const double bw = std::max(0.02, range / 1000);
  const int B = static_cast<int>(range / bw) + 1;
  out.levels.u0 = u_min, out.levels.bin = bw;
  auto bin_of = [&](double v) {
    return static_cast<int>(std::clamp(std::floor((v - u_min) / bw), 0.0, B - 1.0));
  };
  // Per bin: its nodes' hi, sorted; the highest lo of the nodes in it and every bin below (z of
  // a range ending there).
  std::vector<std::vector<double>> his(static_cast<std::size_t>(B));
  std::vector<double> top_lo(static_cast<std::size_t>(B), -std::numeric_limits<double>::infinity());
  for (std::size_t k = 0; k < n; ++k) {
    const auto b = static_cast<std::size_t>(bin_of(u[k]));
    his[b].push_back(hi[k]);
    top_lo[b] = std::max(top_lo[b], lo[k]);
  }
  for (auto& v : his) std::sort(v.begin(), v.end());
  for (std::size_t b = 1; b < top_lo.size(); ++b) top_lo[b] = std::max(top_lo[b], top_lo[b - 1]);
  // best[L][b + 1]: the most nodes within their level with L ranges over bins 0 … b; from[L][b + 1]
  // the first bin of the last range. A range a … b holds count(a, b) = row[b + 1] − row[a] of
  // its nodes, row[a] the nodes of bins < a that top_lo[b] lies within (hi >= it); row is made
  // for one b at a time, its bins' lower bounds moving up with top_lo (non-decreasing), so the
  // work is O(B²) without a B × B table (4 MB at B = 1000, written afresh for each shell).
  const auto W = static_cast<std::size_t>(B) + 1;
  const auto L_max = static_cast<std::size_t>(max_levels);
  std::vector<std::vector<int>> best(L_max + 1, std::vector<int>(W, 0)), from = best;
  std::vector<int> row(W, 0);
  std::vector<std::size_t> first_within(static_cast<std::size_t>(B), 0);
  for (int b = 0; b < B; ++b) {
    const double z = top_lo[static_cast<std::size_t>(b)];
    for (int a = 0; a <= b; ++a) {
      const auto& h = his[static_cast<std::size_t>(a)];
      std::size_t& k = first_within[static_cast<std::size_t>(a)];
      while (k < h.size() && h[k] < z) ++k;
      row[static_cast<std::size_t>(a) + 1] =
          row[static_cast<std::size_t>(a)] + static_cast<int>(h.size() - k);
    }
    const int* r = row.data();
    const auto e = static_cast<std::size_t>(b) + 1;
    best[1][e] = r[b + 1] - r[0];
    for (std::size_t L = 2; L <= L_max; ++L) {
      best[L][e] = best[L - 1][e], from[L][e] = from[L - 1][e];
      for (int a = 1; a <= b; ++a) {
        const int v = best[L - 1][static_cast<std::size_t>(a)] + r[b + 1] - r[a];
        if (v > best[L][e]) best[L][e] = v, from[L][e] = a;
      }
    }
  }
  // As few levels as come within 2 % of the most: each is printed apart, like a band.
  std::size_t L = 1;
  const auto end = static_cast<std::size_t>(B);
  while (L < L_max && best[L][end] < best[L_max][end] - 0.02 * static_cast<double>(n)) ++L;
  out.banded = 1.0 - best[L][end] / static_cast<double>(n);
  // The ranges, last first.
  std::vector<std::pair<int, int>> ranges;
  for (int b = B - 1; L >= 1 && b >= 0; --L) {
    const int a = L == 1 ? 0 : from[L][static_cast<std::size_t>(b) + 1];
    ranges.emplace_back(a, b);
    b = a - 1;
    if (b < 0) break;
  }
  std::reverse(ranges.begin(), ranges.end());
  for (const auto& [a, b] : ranges) {
    out.levels.z.push_back(top_lo[static_cast<std::size_t>(b)]);
    out.levels.last.push_back(b);
  }
  return out;
}

}  // namespace nonplanar::layers
