// The highest material laid so far over each 1 mm cell of the bed, as a program is written in
// print order: what a travel must clear where layers are printed out of order (a shell's
// pieces after core layers standing higher than they do; a planar object's layer after a
// curved layer of another that rose above it).
#pragma once

#include <limits>
#include <vector>

#include "nonplanar/mesh.hpp"

namespace nonplanar::program {

/// mm beside a travel's path, past the nozzle tip's radius, that it must clear.
inline constexpr double kTravelCorridor = 1.0;

class PrintedTop {
 public:
  /// No cells yet: they are made round the first bead laid. Cells lie on a 1 mm lattice from
  /// (0, 0) then, and are added (the grid grown) for a bead laid off them, up to 4096 cells on
  /// a side; a point past that is not kept.
  PrintedTop() = default;
  /// Cells over [lo, hi] (mm, XY) to start with, 1 mm square, on the lattice from lo.
  PrintedTop(const Vec2& lo, const Vec2& hi);
  /// A bead laid from a to b (the nozzle's tip, mm): every cell it crosses.
  void lay(const Vec3& a, const Vec3& b);
  /// The highest material laid within `r` mm of the segment a–b seen from above (its cells,
  /// grown by r); -inf when none.
  double over(const Vec2& a, const Vec2& b, double r) const;
  /// What a travel from a to b over a layer whose top is `top` must clear (mm): the highest
  /// material laid within `r` of its way, where that stands higher than `top` and both ends;
  /// else `top`.
  double to_clear(const Vec3& a, const Vec3& b, double r, double top) const;

 private:
  void lay(const Vec3& p);
  /// Makes cells over p, keeping the lattice and what was laid; false when it cannot.
  bool grow(const Vec2& p);
  Vec2 lo_{0, 0};
  double highest_ = -std::numeric_limits<double>::infinity();
  int nx_ = 0, ny_ = 0;
  std::vector<float> top_;  ///< nx × ny, -inf where nothing is laid
};

}  // namespace nonplanar::program
