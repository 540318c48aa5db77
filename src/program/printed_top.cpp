// PrintedTop (printed_top.hpp): the highest material laid so far, per 1 mm cell.
#include "program/printed_top.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nonplanar::program {

namespace {
constexpr double kCell = 1.0;        ///< mm
constexpr int kMostCells = 1 << 22;  ///< a 2 m bed at 1 mm; past it no cells (nothing to clear)
}  // namespace

PrintedTop::PrintedTop(const Vec2& lo, const Vec2& hi) : lo_(lo) {
  const Vec2 size = (hi - lo).cwiseMax(Vec2(0, 0));
  if (!size.allFinite()) return;
  nx_ = static_cast<int>(std::min(size.x() / kCell, 4096.0)) + 1;
  ny_ = static_cast<int>(std::min(size.y() / kCell, 4096.0)) + 1;
  if (static_cast<long>(nx_) * ny_ > kMostCells) nx_ = ny_ = 0;
  top_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_),
              -std::numeric_limits<float>::infinity());
}

void PrintedTop::lay(const Vec3& a, const Vec3& b) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).head<2>().norm() / (0.5 * kCell))));
  for (int k = 0; k <= n; ++k) lay(a + (b - a) * (static_cast<double>(k) / n));
}

bool PrintedTop::grow(const Vec2& p) {
  if (!p.allFinite() || p.cwiseAbs().maxCoeff() > 1e6) return false;
  if (top_.empty()) lo_ = (p / kCell).array().floor().matrix() * kCell, nx_ = ny_ = 0;
  // The cells' index box, grown over p with room to spare (16 mm, or half again the side it
  // grows: a file's beads come a few at a time, each growth copies the grid).
  long i0 = 0, j0 = 0, i1 = nx_, j1 = ny_;  // [i0, i1) x [j0, j1) in the old cells' indices
  const auto fi = static_cast<long>(std::floor((p.x() - lo_.x()) / kCell)),
             fj = static_cast<long>(std::floor((p.y() - lo_.y()) / kCell));
  const long mx = std::max(16L, long{nx_} / 2), my = std::max(16L, long{ny_} / 2);
  if (fi < i0) i0 = fi - mx;
  if (fi >= i1) i1 = fi + 1 + mx;
  if (fj < j0) j0 = fj - my;
  if (fj >= j1) j1 = fj + 1 + my;
  const long nx = i1 - i0, ny = j1 - j0;
  if (nx > 4096 || ny > 4096 || nx * ny > kMostCells) return false;
  std::vector<float> top(static_cast<std::size_t>(nx * ny),
                         -std::numeric_limits<float>::infinity());
  for (long i = 0; i < nx_; ++i)
    std::copy_n(top_.begin() + i * ny_, ny_, top.begin() + (i - i0) * ny - j0);
  top_ = std::move(top);
  lo_ += Vec2(static_cast<double>(i0) * kCell, static_cast<double>(j0) * kCell);
  nx_ = static_cast<int>(nx), ny_ = static_cast<int>(ny);
  return true;
}

void PrintedTop::lay(const Vec3& p) {
  highest_ = std::max(highest_, p.z());
  double fx = std::floor((p.x() - lo_.x()) / kCell), fy = std::floor((p.y() - lo_.y()) / kCell);
  if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) {
    if (!grow(p.head<2>())) return;
    fx = std::floor((p.x() - lo_.x()) / kCell), fy = std::floor((p.y() - lo_.y()) / kCell);
  }
  float& t = top_[static_cast<std::size_t>(fx) * static_cast<std::size_t>(ny_) +
                  static_cast<std::size_t>(fy)];
  t = std::max(t, static_cast<float>(p.z()));
}

double PrintedTop::over(const Vec2& a, const Vec2& b, double r) const {
  double best = -std::numeric_limits<double>::infinity();
  if (top_.empty()) return best;
  // The cells within r of the segment: those whose centre is within r + a cell's half
  // diagonal of it, in the segment's box grown by r.
  const Vec2 lo = a.cwiseMin(b) - Vec2(r, r), hi = a.cwiseMax(b) + Vec2(r, r);
  const int i0 = std::max(0, static_cast<int>(std::floor((lo.x() - lo_.x()) / kCell)));
  const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() - lo_.x()) / kCell)));
  const int j0 = std::max(0, static_cast<int>(std::floor((lo.y() - lo_.y()) / kCell)));
  const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() - lo_.y()) / kCell)));
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm(), reach = r + 0.7072 * kCell;
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const float t = top_[static_cast<std::size_t>(i) * static_cast<std::size_t>(ny_) +
                           static_cast<std::size_t>(j)];
      if (t <= best) continue;
      const Vec2 c = lo_ + Vec2((i + 0.5) * kCell, (j + 0.5) * kCell);
      const double s = len2 > 0 ? std::clamp((c - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      if ((a + s * ab - c).norm() <= reach) best = t;
    }
  return best;
}

double PrintedTop::to_clear(const Vec3& a, const Vec3& b, double r, double top) const {
  const double ends = std::max({top, a.z(), b.z()});
  if (highest_ <= ends) return top;  // (most travels: nothing laid stands that high)
  return std::max(top, over(a.head<2>(), b.head<2>(), r));
}

}  // namespace nonplanar::program
