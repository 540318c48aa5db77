// Normal equations JᵀJ x = Jᵀr for unknowns on a tensor-product control grid.
//
// Notation: the grid has n_u × n_v cells; an unknown is (block b, cell i·n_v + j), with B
// blocks (1 for heights z_ij; 2 for the rational form's a_ij = w_ij z_ij and w_ij). A row of
// J touches only cells within ±p in i and ±q in j of each other, so JᵀJ is stored as bands:
// for every block pair and cell, (2p + 1)(2q + 1) coefficients. Accumulating a sample costs
// (m · B)² multiply-adds for its m = (p + 1)(q + 1) basis functions, and no sparse product.
#pragma once

#include <Eigen/Sparse>
#include <vector>

namespace nonplanar::nurbs {

class GridNormalEquations {
 public:
  GridNormalEquations(int n_u, int n_v, int p, int q, int blocks);

  /// One residual row: coefficients c[b][a·(q+1) + c] for the cells (i0 + a, j0 + c),
  /// a ≤ p, c ≤ q, of each block b; target t and row weight s (the row is scaled by s).
  void add_row(int i0, int j0, const double* const* coef, double target, double s = 1.0);

  /// Adds λ·M to block (0, 0) (or (b, b)) where M is a banded matrix given per cell like the
  /// bands here: m[cell · band_width() + offset].
  void add_banded(const std::vector<double>& m, double lambda, int block = 0);
  /// Adds the one-entry row c·x[block, cell] ≈ target (JᵀJ += c², Jᵀr += c·target).
  void add_entry(int block, int cell, double c, double target);
  /// Adds λ to the diagonal of a block (Tikhonov) and λ·x0 to its right-hand side.
  void add_diagonal(double lambda, int block, double x0 = 0.0);

  int band_width() const { return (2 * p_ + 1) * (2 * q_ + 1); }
  int band_index(int di, int dj) const { return (di + p_) * (2 * q_ + 1) + (dj + q_); }
  int unknowns() const { return blocks_ * n_; }
  const Eigen::VectorXd& rhs() const { return rhs_; }

  /// Solves with a sparse LDLᵀ factorisation; false when it is not positive definite.
  bool solve(Eigen::VectorXd* x) const;

 private:
  int n_u_, n_v_, p_, q_, blocks_, n_;
  std::vector<double> band_;  // [(bk · B + bl) · n + cell] · band_width + offset
  Eigen::VectorXd rhs_;
};

/// The thin-plate energy ∫∫ S_xx² + 2 S_xy² + S_yy² dx dy of a polynomial spline over the
/// footprint sx × sy, as a banded matrix on the control grid (Gauss quadrature per span).
std::vector<double> thin_plate_bands(const std::vector<double>& U, const std::vector<double>& V,
                                     int p, int q, double sx, double sy);

}  // namespace nonplanar::nurbs
