// When each piece of a shell beside taller material is printed: the target g(u), a
// non-decreasing step function of a shell point's height u (shell_region.hpp).
//
// Notation as in shell_region.hpp: a shell point p of height u = U_j(p) has the interval
// [lo, hi] = [u − s⁻(p), u + s(p)] of times it may be printed at; τ(p) = clamp(g(u), lo, hi).
//
// Why steps: one height Z for the whole patch (g constant) suits a level top, but on a sloped
// one beside a rim most points cannot wait for Z and follow the wall up in bands, each printed
// apart (the airfoil rib: 47 % of its top banded with one height, and only its largest patch
// within the limit). A few heights, each for the points within a range of u, cover more: all
// four of its patches, 17 % banded, with eight. Any non-decreasing g keeps
// the shell's order safe: if p is printed before q and stands higher, g(u_p) >= g(u_q), so
// one of them is clamped, and each case bounds u_p − u_q by a difference of k-Lipschitz
// slacks (the proof of shell_region.hpp with Z replaced by g(u); the header there gives it).
#pragma once

#include <limits>
#include <vector>

namespace nonplanar::layers {

struct ShellLevels {
  /// u falls in bin floor((u − u0) / bin), clamped to 0 … last[back]; bins up to last[0] take
  /// z[0], then up to last[1] z[1], and so on (the bins the levels were chosen on, so a node
  /// at a bin's edge takes the level it was counted for). z non-decreasing, mm. Empty: every
  /// point after the core.
  double u0 = 0, bin = 1;
  std::vector<int> last;
  std::vector<double> z;
  bool empty() const { return z.empty(); }
  double at(double u) const;
};

struct LevelChoice {
  ShellLevels levels;
  /// The share of the nodes whose interval holds no level of g (printed in bands).
  double banded = 0;
};

/// Inputs: each patch node's height u = H and its interval [lo, hi] (mm, lo <= u <= hi; all
/// three the same size), and the most levels to use. Output: g, with as few levels as reach
/// within 2 % of the share that max_levels reach, and the share of nodes left banded. Each
/// level's range of u is a run of 0.02 mm bins (coarser for tall patches: at most 1000) and its
/// height the highest lo among the nodes up to that range's top, so every node of the range
/// is printed no earlier than it may be.
LevelChoice choose_levels(const std::vector<double>& u, const std::vector<double>& lo,
                          const std::vector<double>& hi, int max_levels);

}  // namespace nonplanar::layers
