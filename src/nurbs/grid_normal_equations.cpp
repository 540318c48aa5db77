#include "nurbs/grid_normal_equations.hpp"

#include <Eigen/SparseCholesky>
#include <array>

#include "nurbs/bspline_basis.hpp"

namespace nonplanar::nurbs {

GridNormalEquations::GridNormalEquations(int n_u, int n_v, int p, int q, int blocks)
    : n_u_(n_u), n_v_(n_v), p_(p), q_(q), blocks_(blocks), n_(n_u * n_v) {
  band_.assign(static_cast<std::size_t>(blocks_ * blocks_) * n_ * band_width(), 0.0);
  rhs_ = Eigen::VectorXd::Zero(blocks_ * n_);
}

void GridNormalEquations::add_row(int i0, int j0, const double* const* coef, double target,
                                  double s) {
  const int m_u = p_ + 1, m_v = q_ + 1, bw = band_width();
  const double s2 = s * s;
  for (int bk = 0; bk < blocks_; ++bk) {
    const double* ck = coef[bk];
    for (int a = 0; a < m_u; ++a)
      for (int c = 0; c < m_v; ++c) {
        const double x = ck[a * m_v + c] * s2;
        if (x == 0.0) continue;
        const int cell = (i0 + a) * n_v_ + (j0 + c);
        rhs_[bk * n_ + cell] += x * target;
        for (int bl = 0; bl < blocks_; ++bl) {
          const double* cl = coef[bl];
          double* row = &band_[(static_cast<std::size_t>(bk * blocks_ + bl) * n_ + cell) * bw];
          for (int a2 = 0; a2 < m_u; ++a2) {
            double* r = row + band_index(a2 - a, -c);
            const double* cc = cl + a2 * m_v;
            for (int c2 = 0; c2 < m_v; ++c2) r[c2] += x * cc[c2];
          }
        }
      }
  }
}

void GridNormalEquations::add_banded(const std::vector<double>& m, double lambda, int block) {
  const std::size_t off = static_cast<std::size_t>(block * blocks_ + block) * n_ * band_width();
  for (std::size_t k = 0; k < m.size(); ++k) band_[off + k] += lambda * m[k];
}

void GridNormalEquations::add_entry(int block, int cell, double c, double target) {
  const std::size_t off = static_cast<std::size_t>(block * blocks_ + block) * n_ * band_width();
  band_[off + static_cast<std::size_t>(cell) * band_width() + band_index(0, 0)] += c * c;
  rhs_[block * n_ + cell] += c * target;
}

void GridNormalEquations::add_diagonal(double lambda, int block, double x0) {
  const std::size_t off = static_cast<std::size_t>(block * blocks_ + block) * n_ * band_width();
  for (int cell = 0; cell < n_; ++cell) {
    band_[off + static_cast<std::size_t>(cell) * band_width() + band_index(0, 0)] += lambda;
    rhs_[block * n_ + cell] += lambda * x0;
  }
}

bool GridNormalEquations::solve(Eigen::VectorXd* x) const {
  std::vector<Eigen::Triplet<double>> trips;
  trips.reserve(band_.size() / 2);
  const int bw = band_width();
  for (int bk = 0; bk < blocks_; ++bk)
    for (int bl = 0; bl < blocks_; ++bl)
      for (int cell = 0; cell < n_; ++cell) {
        const int i = cell / n_v_, j = cell % n_v_;
        const double* row = &band_[(static_cast<std::size_t>(bk * blocks_ + bl) * n_ + cell) * bw];
        for (int di = -p_; di <= p_; ++di)
          for (int dj = -q_; dj <= q_; ++dj) {
            const double v = row[band_index(di, dj)];
            if (v == 0.0 || i + di < 0 || i + di >= n_u_ || j + dj < 0 || j + dj >= n_v_) continue;
            const int other = (i + di) * n_v_ + (j + dj);
            // Keep the lower triangle only: the factorisation reads that half.
            const int r = bk * n_ + cell, c = bl * n_ + other;
            if (r >= c) trips.emplace_back(r, c, v);
          }
      }
  Eigen::SparseMatrix<double> A(blocks_ * n_, blocks_ * n_);
  A.setFromTriplets(trips.begin(), trips.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt(A);
  if (ldlt.info() != Eigen::Success) return false;
  *x = ldlt.solve(rhs_);
  return ldlt.info() == Eigen::Success && x->allFinite();
}

std::vector<double> thin_plate_bands(const std::vector<double>& U, const std::vector<double>& V,
                                     int p, int q, double sx, double sy) {
  const int n_u = static_cast<int>(U.size()) - p - 1, n_v = static_cast<int>(V.size()) - q - 1;
  const int bw = (2 * p + 1) * (2 * q + 1);
  std::vector<double> m(static_cast<std::size_t>(n_u) * n_v * bw, 0.0);
  // 4-point Gauss–Legendre per span integrates degree 7 exactly: enough for products of
  // cubic basis functions and their derivatives in each direction.
  const std::array<double, 4> gx = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                    0.8611363115940526};
  const std::array<double, 4> gw = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                    0.3478548451374538};
  std::vector<double> du(3 * (p + 1)), dv(3 * (q + 1));
  const double area = sx * sy;
  for (int su = p; su < n_u; ++su) {
    const double u0 = U[su], u1 = U[su + 1];
    if (u1 <= u0) continue;
    for (int sv = q; sv < n_v; ++sv) {
      const double v0 = V[sv], v1 = V[sv + 1];
      if (v1 <= v0) continue;
      for (int a = 0; a < 4; ++a) {
        const double u = 0.5 * (u0 + u1) + 0.5 * (u1 - u0) * gx[a];
        ders_basis_funs(su, u, p, 2, U, du.data());
        for (int b = 0; b < 4; ++b) {
          const double v = 0.5 * (v0 + v1) + 0.5 * (v1 - v0) * gx[b];
          ders_basis_funs(sv, v, q, 2, V, dv.data());
          const double wq = gw[a] * gw[b] * 0.25 * (u1 - u0) * (v1 - v0) * area;
          // Second derivatives in x, y of each basis product N_i(u) N_j(v).
          for (int i1 = 0; i1 <= p; ++i1)
            for (int j1 = 0; j1 <= q; ++j1) {
              const double xx1 = du[2 * (p + 1) + i1] * dv[j1] / (sx * sx);
              const double xy1 = du[(p + 1) + i1] * dv[(q + 1) + j1] / (sx * sy);
              const double yy1 = du[i1] * dv[2 * (q + 1) + j1] / (sy * sy);
              const int cell = (su - p + i1) * n_v + (sv - q + j1);
              for (int i2 = 0; i2 <= p; ++i2)
                for (int j2 = 0; j2 <= q; ++j2) {
                  const double xx2 = du[2 * (p + 1) + i2] * dv[j2] / (sx * sx);
                  const double xy2 = du[(p + 1) + i2] * dv[(q + 1) + j2] / (sx * sy);
                  const double yy2 = du[i2] * dv[2 * (q + 1) + j2] / (sy * sy);
                  const int off = (i2 - i1 + p) * (2 * q + 1) + (j2 - j1 + q);
                  m[static_cast<std::size_t>(cell) * bw + off] +=
                      wq * (xx1 * xx2 + 2 * xy1 * xy2 + yy1 * yy2);
                }
            }
        }
      }
    }
  }
  return m;
}

}  // namespace nonplanar::nurbs
