// Rational surface evaluation in homogeneous coordinates (Piegl & Tiller A3.5/A3.6, A4.3,
// A4.4) and knot insertion (A5.1 applied to every row or column of the control net).
//
// Notation: A(u, v) = Σ N_i N_j w_ij P_ij and W(u, v) = Σ N_i N_j w_ij, so S = A / W; their
// partial derivatives are A^(k,l) and W^(k,l).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "nonplanar/nurbs.hpp"
#include "nurbs/bspline_basis.hpp"

namespace nonplanar {

using nurbs::basis_funs;
using nurbs::ders_basis_funs;
using nurbs::find_span;
using Vec4 = Eigen::Vector4d;

namespace {

constexpr int kMaxDeg = 7;

double binomial(int n, int k) {
  double r = 1;
  for (int i = 1; i <= k; ++i) r = r * (n - k + i) / i;
  return r;
}

bool knots_ok(const std::vector<double>& K, int deg, int n) {
  if (deg < 1 || deg > kMaxDeg || n <= deg) return false;
  if (static_cast<int>(K.size()) != n + deg + 1) return false;
  for (std::size_t i = 1; i < K.size(); ++i)
    if (!(K[i] >= K[i - 1]) || !std::isfinite(K[i])) return false;
  return K[deg] < K[n];
}

// One row of homogeneous points with knot insertion (A5.1), r times at u.
void insert_knot_curve(int p, std::vector<double>& UP, std::vector<Vec4>& Pw, double u, int r) {
  const int n = static_cast<int>(Pw.size());
  const int np = n - 1;
  const int k = find_span(n, p, u, UP);
  int s = 0;
  for (double t : UP) s += t == u;
  r = std::min(r, p - s);
  if (r <= 0) return;
  const int mp = np + p + 1;
  std::vector<double> UQ(UP.size() + r);
  for (int i = 0; i <= k; ++i) UQ[i] = UP[i];
  for (int i = 1; i <= r; ++i) UQ[k + i] = u;
  for (int i = k + 1; i <= mp; ++i) UQ[i + r] = UP[i];
  std::vector<Vec4> Qw(n + r);
  for (int i = 0; i <= k - p; ++i) Qw[i] = Pw[i];
  for (int i = k - s; i <= np; ++i) Qw[i + r] = Pw[i];
  std::vector<Vec4> Rw(p + 1);
  for (int i = 0; i <= p - s; ++i) Rw[i] = Pw[k - p + i];
  int L = 0;
  for (int j = 1; j <= r; ++j) {
    L = k - p + j;
    for (int i = 0; i <= p - j - s; ++i) {
      const double alpha = (u - UP[L + i]) / (UP[i + k + 1] - UP[L + i]);
      Rw[i] = alpha * Rw[i + 1] + (1.0 - alpha) * Rw[i];
    }
    Qw[L] = Rw[0];
    Qw[k + r - j - s] = Rw[p - j - s];
  }
  for (int i = L + 1; i < k - s; ++i) Qw[i] = Rw[i - L];
  UP = std::move(UQ);
  Pw = std::move(Qw);
}

}  // namespace

std::vector<double> uniform_knots(int p, int spans) {
  std::vector<double> U;
  for (int i = 0; i < p; ++i) U.push_back(0.0);
  for (int i = 0; i <= spans; ++i) U.push_back(static_cast<double>(i) / spans);
  for (int i = 0; i < p; ++i) U.push_back(1.0);
  return U;
}

bool NurbsSurface::valid() const {
  const std::size_t n = static_cast<std::size_t>(n_u) * static_cast<std::size_t>(n_v);
  if (!knots_ok(U, p, n_u) || !knots_ok(V, q, n_v)) return false;
  if (points.size() != n || weights.size() != n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (!(weights[i] > 0) || !std::isfinite(weights[i]) || !points[i].allFinite()) return false;
  return true;
}

std::array<std::array<Vec3, 3>, 3> NurbsSurface::derivatives(double u, double v, int d) const {
  d = std::clamp(d, 0, 2);
  u = std::clamp(u, U[p], U[n_u]);
  v = std::clamp(v, V[q], V[n_v]);
  const int su = find_span(n_u, p, u, U), sv = find_span(n_v, q, v, V);
  const int du = std::min(d, p), dv = std::min(d, q);
  double Nu[3 * (kMaxDeg + 1)] = {}, Nv[3 * (kMaxDeg + 1)] = {};
  ders_basis_funs(su, u, p, du, U, Nu);
  ders_basis_funs(sv, v, q, dv, V, Nv);
  // Homogeneous derivatives: H^(k,l) = (A^(k,l), W^(k,l)).
  Vec4 H[3][3];
  for (auto& row : H)
    for (auto& h : row) h.setZero();
  for (int a = 0; a <= p; ++a) {
    const int i = su - p + a;
    for (int b = 0; b <= q; ++b) {
      const int j = sv - q + b;
      const double wij = w(i, j);
      Vec4 pw;
      pw << wij * P(i, j), wij;
      for (int k = 0; k <= du; ++k)
        for (int l = 0; l <= dv && k + l <= d; ++l)
          H[k][l] += Nu[k * (p + 1) + a] * Nv[l * (q + 1) + b] * pw;
    }
  }
  // Quotient rule (A4.4): S^(k,l) = (A^(k,l) − Σ binomial terms) / W.
  std::array<std::array<Vec3, 3>, 3> S{};
  for (int k = 0; k <= d; ++k)
    for (int l = 0; l + k <= d; ++l) {
      Vec3 t = H[k][l].head<3>();
      for (int j = 1; j <= l; ++j) t -= binomial(l, j) * H[0][j][3] * S[k][l - j];
      for (int i = 1; i <= k; ++i) {
        t -= binomial(k, i) * H[i][0][3] * S[k - i][l];
        Vec3 t2 = Vec3::Zero();
        for (int j = 1; j <= l; ++j) t2 += binomial(l, j) * H[i][j][3] * S[k - i][l - j];
        t -= binomial(k, i) * t2;
      }
      S[k][l] = t / H[0][0][3];
    }
  return S;
}

Vec3 NurbsSurface::evaluate(double u, double v) const {
  u = std::clamp(u, U[p], U[n_u]);
  v = std::clamp(v, V[q], V[n_v]);
  const int su = find_span(n_u, p, u, U), sv = find_span(n_v, q, v, V);
  double Nu[kMaxDeg + 1], Nv[kMaxDeg + 1];
  basis_funs(su, u, p, U, Nu);
  basis_funs(sv, v, q, V, Nv);
  Vec3 a = Vec3::Zero();
  double wsum = 0;
  for (int i = 0; i <= p; ++i)
    for (int j = 0; j <= q; ++j) {
      const double c = Nu[i] * Nv[j] * w(su - p + i, sv - q + j);
      a += c * P(su - p + i, sv - q + j);
      wsum += c;
    }
  return a / wsum;
}

Vec3 NurbsSurface::normal(double u, double v) const {
  const auto d = derivatives(u, v, 1);
  const Vec3 n = d[1][0].cross(d[0][1]);
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

void NurbsSurface::insert_knot_u(double u, int r) {
  // Each column j (fixed v index) is a curve in u.
  std::vector<double> newU;
  std::vector<std::vector<Vec4>> cols(n_v);
  for (int j = 0; j < n_v; ++j) {
    std::vector<Vec4> Pw(n_u);
    for (int i = 0; i < n_u; ++i) Pw[i] << w(i, j) * P(i, j), w(i, j);
    std::vector<double> UP = U;
    insert_knot_curve(p, UP, Pw, u, r);
    cols[j] = std::move(Pw);
    newU = std::move(UP);
  }
  const int nn = static_cast<int>(cols[0].size());
  points.assign(static_cast<std::size_t>(nn) * n_v, Vec3::Zero());
  weights.assign(static_cast<std::size_t>(nn) * n_v, 1.0);
  for (int i = 0; i < nn; ++i)
    for (int j = 0; j < n_v; ++j) {
      const Vec4& h = cols[j][i];
      points[static_cast<std::size_t>(i) * n_v + j] = h.head<3>() / h[3];
      weights[static_cast<std::size_t>(i) * n_v + j] = h[3];
    }
  n_u = nn;
  U = std::move(newU);
}

namespace {

// The same surface with u and v swapped (P_ij ↦ P_ji): a v-direction operation is the
// u-direction one on the transpose.
NurbsSurface transposed(const NurbsSurface& s) {
  NurbsSurface t;
  t.p = s.q, t.q = s.p, t.n_u = s.n_v, t.n_v = s.n_u, t.U = s.V, t.V = s.U;
  t.points.resize(s.points.size());
  t.weights.resize(s.weights.size());
  for (int i = 0; i < s.n_u; ++i)
    for (int j = 0; j < s.n_v; ++j) {
      t.points[static_cast<std::size_t>(j) * s.n_u + i] = s.P(i, j);
      t.weights[static_cast<std::size_t>(j) * s.n_u + i] = s.w(i, j);
    }
  return t;
}

}  // namespace

void NurbsSurface::insert_knot_v(double v, int r) {
  NurbsSurface t = transposed(*this);
  t.insert_knot_u(v, r);
  *this = transposed(t);
}

double HeightField::height(double x, double y) const {
  const Vec2 t = uv(x, y);
  return surface.evaluate(t.x(), t.y()).z();
}

Vec2 HeightField::gradient(double x, double y) const {
  const Vec2 t = uv(x, y);
  const auto d = surface.derivatives(t.x(), t.y(), 1);
  return {d[1][0].z() / extent.x(), d[0][1].z() / extent.y()};
}

}  // namespace nonplanar
