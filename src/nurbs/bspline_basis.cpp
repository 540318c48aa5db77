#include "nurbs/bspline_basis.hpp"

#include <algorithm>
#include <array>

namespace nonplanar::nurbs {

namespace {
constexpr int kMaxDegree = 7;
}

int find_span(int n, int p, double u, const std::vector<double>& U) {
  if (u >= U[n]) return n - 1;
  if (u <= U[p]) return p;
  // First knot greater than u, minus one: the span [U[i], U[i+1]).
  const auto it = std::upper_bound(U.begin() + p, U.begin() + n + 1, u);
  return static_cast<int>(it - U.begin()) - 1;
}

void basis_funs(int i, double u, int p, const std::vector<double>& U, double* N) {
  std::array<double, kMaxDegree + 1> left{}, right{};
  N[0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - U[i + 1 - j];
    right[j] = U[i + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double temp = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    N[j] = saved;
  }
}

void ders_basis_funs(int i, double u, int p, int d, const std::vector<double>& U, double* ders) {
  std::array<std::array<double, kMaxDegree + 1>, kMaxDegree + 1> ndu{}, a{};
  std::array<double, kMaxDegree + 1> left{}, right{};
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - U[i + 1 - j];
    right[j] = U[i + j] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];  // lower triangle: knot differences
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;  // upper triangle: basis functions
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  const int w = p + 1;
  for (int j = 0; j <= p; ++j) ders[j] = ndu[j][p];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0, s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= d; ++k) {
      double dd = 0.0;
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        dd = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        dd += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        dd += a[s2][k] * ndu[r][pk];
      }
      ders[k * w + r] = dd;
      std::swap(s1, s2);
    }
  }
  int r = p;
  for (int k = 1; k <= d; ++k) {
    for (int j = 0; j <= p; ++j) ders[k * w + j] *= r;
    r *= (p - k);
  }
}

}  // namespace nonplanar::nurbs
