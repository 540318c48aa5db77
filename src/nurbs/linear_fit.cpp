#include <algorithm>
#include <cmath>

#include "nurbs/bspline_basis.hpp"
#include "nurbs/fit_internal.hpp"
#include "nurbs/grid_normal_equations.hpp"

namespace nonplanar::nurbs {

void SampleBasis::compute(const NurbsSurface& s, const std::vector<Vec3>& uvz) {
  const std::size_t n = uvz.size();
  const int mu = s.p + 1, mv = s.q + 1;
  su.resize(n);
  sv.resize(n);
  nu.resize(n * mu);
  nv.resize(n * mv);
  for (std::size_t k = 0; k < n; ++k) {
    const double u = std::clamp(uvz[k].x(), s.U[s.p], s.U[s.n_u]);
    const double v = std::clamp(uvz[k].y(), s.V[s.q], s.V[s.n_v]);
    su[k] = find_span(s.n_u, s.p, u, s.U);
    sv[k] = find_span(s.n_v, s.q, v, s.V);
    basis_funs(su[k], u, s.p, s.U, &nu[k * mu]);
    basis_funs(sv[k], v, s.q, s.V, &nv[k * mv]);
  }
}

double sample_height(const NurbsSurface& s, const SampleBasis& b, int k, double* denominator) {
  const int mu = s.p + 1, mv = s.q + 1;
  const int i0 = b.su[k] - s.p, j0 = b.sv[k] - s.q;
  double num = 0, den = 0;
  for (int a = 0; a < mu; ++a)
    for (int c = 0; c < mv; ++c) {
      const std::size_t idx = static_cast<std::size_t>(i0 + a) * s.n_v + (j0 + c);
      const double nw = b.nu[k * mu + a] * b.nv[k * mv + c] * s.weights[idx];
      num += nw * s.points[idx].z();
      den += nw;
    }
  if (denominator) *denominator = den;
  return num / den;
}

double residuals(const NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                 std::vector<double>* r, double* max) {
  r->resize(uvz.size());
  double ss = 0, mx = 0;
  for (std::size_t k = 0; k < uvz.size(); ++k) {
    (*r)[k] = sample_height(s, b, static_cast<int>(k)) - uvz[k].z();
    ss += (*r)[k] * (*r)[k];
    mx = std::max(mx, std::abs((*r)[k]));
  }
  if (max) *max = mx;
  return uvz.empty() ? 0.0 : std::sqrt(ss / static_cast<double>(uvz.size()));
}

bool fit_polynomial(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                    double lambda, double sx, double sy) {
  const int mu = s.p + 1, mv = s.q + 1;
  GridNormalEquations ne(s.n_u, s.n_v, s.p, s.q, 1);
  std::vector<double> coef(static_cast<std::size_t>(mu) * mv);
  const double* rows[1] = {coef.data()};
  for (std::size_t k = 0; k < uvz.size(); ++k) {
    for (int a = 0; a < mu; ++a)
      for (int c = 0; c < mv; ++c) coef[a * mv + c] = b.nu[k * mu + a] * b.nv[k * mv + c];
    ne.add_row(b.su[k] - s.p, b.sv[k] - s.q, rows, uvz[k].z());
  }
  ne.add_banded(thin_plate_bands(s.U, s.V, s.p, s.q, sx, sy), lambda);
  Eigen::VectorXd x;
  if (!ne.solve(&x)) return false;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    s.points[i].z() = x[static_cast<Eigen::Index>(i)];
    s.weights[i] = 1.0;
  }
  return true;
}

double fit_rational_linearised(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                               double lambda, double sx, double sy, const FitParams& params) {
  const int mu = s.p + 1, mv = s.q + 1;
  const int n = s.n_u * s.n_v;
  std::vector<double> r;
  double best = residuals(s, b, uvz, &r, nullptr);
  NurbsSurface best_s = s;
  const std::vector<double> tp = thin_plate_bands(s.U, s.V, s.p, s.q, sx, sy);
  std::vector<double> ca(static_cast<std::size_t>(mu) * mv), cw(ca.size());
  const double* rows[2] = {ca.data(), cw.data()};
  // Pull of the weights towards 1: it also fixes the scale (a, w) ~ (c·a, c·w) that the
  // homogeneous equations leave free.
  const double gamma = 1e-6 * static_cast<double>(uvz.size()) / n;
  for (int iter = 0; iter < 8; ++iter) {
    GridNormalEquations ne(s.n_u, s.n_v, s.p, s.q, 2);
    for (std::size_t k = 0; k < uvz.size(); ++k) {
      const int i0 = b.su[k] - s.p, j0 = b.sv[k] - s.q;
      double den = 0;
      for (int a = 0; a < mu; ++a)
        for (int c = 0; c < mv; ++c) {
          const double nn = b.nu[k * mu + a] * b.nv[k * mv + c];
          ca[a * mv + c] = nn;
          cw[a * mv + c] = -uvz[k].z() * nn;
          den += nn * s.weights[static_cast<std::size_t>(i0 + a) * s.n_v + (j0 + c)];
        }
      ne.add_row(i0, j0, rows, 0.0, 1.0 / den);
    }
    ne.add_banded(tp, lambda, 0);
    ne.add_banded(tp, lambda, 1);
    ne.add_diagonal(gamma, 1, 1.0);
    Eigen::VectorXd x;
    if (!ne.solve(&x)) break;
    double mean_w = 0;
    for (int i = 0; i < n; ++i) mean_w += x[n + i];
    mean_w /= n;
    if (!(mean_w > 0)) break;
    for (int i = 0; i < n; ++i) {
      const double w = std::clamp(x[n + i] / mean_w, params.weight_min, params.weight_max);
      s.points[i].z() = (x[i] / mean_w) / (x[n + i] / mean_w);
      s.weights[i] = w;
      if (!std::isfinite(s.points[i].z())) s.points[i].z() = best_s.points[i].z();
    }
    const double rms = residuals(s, b, uvz, &r, nullptr);
    const bool improved = rms < best * 0.99;
    if (rms < best) best = rms, best_s = s;
    if (!improved) break;
  }
  s = best_s;
  return best;
}

}  // namespace nonplanar::nurbs
