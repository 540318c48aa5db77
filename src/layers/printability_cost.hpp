// The printability cost of a layer stack (paper eq. 1, plus the printer's slope and heater-
// block limits) and its analytic gradient with respect to the intermediate layers' control
// heights.
//
// Notation: samples k on a grid over the stack's rectangle, area a_k; R_kj the rational basis
// of control point j at sample k (all layers share knots and weights, so S_i(k) = Σ_j R_kj
// z_ij and ∇S_i(k) = Σ_j ∇R_kj z_ij); t_ik = S_i(k) − S_{i+1}(k).
//   C = Σ_k m_k a_k [ Σ_i (t_ik − h)²                       (eq. 1, squared: smooth)
//                   + λ Σ_i |∇S_i − ∇S_{i+1}|²            (continuity)
//                   + μ Σ_i (max(0, h_min − t)² + max(0, t − h_max)²)
//                   + μ Σ_i max(0, |∇S_i| − g)² ]        (slope: g = tan α)
//     + μ Σ_i Σ_(k,l) max(0, S_i(l) − S_i(k) − H)²          (heater block: pairs of samples
//                                                              on the patch within radius R)
// with m_k = 1 on the patch, 0 in the margin around it: the limits there are the blend
// check's (the fit off the patch can swing by millimetres), so such a sample costs nothing.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "nonplanar/layers.hpp"

namespace nonplanar::layers {

struct StackGrid {
  std::vector<Vec2> xy;
  std::vector<double> area;
  std::vector<char> on_patch;
  int m = 0;                      ///< basis functions per sample, (p+1)(q+1)
  std::vector<int> ctrl;          ///< m per sample: control index of each basis function
  std::vector<double> R, Rx, Ry;  ///< m per sample: basis, ∂/∂x, ∂/∂y
  int nx = 0, ny = 0;             ///< sample k = i·ny + j at (i + ½, j + ½)·step
  double step_x = 0, step_y = 0;
  std::vector<std::pair<int, int>> block_pairs;  ///< (k, l): l within the block radius of k

  /// Fills block_pairs on a subgrid of about `spacing` mm over the patch's samples.
  void pair_within(double radius, double spacing);

  /// Control index of the a-th basis function of sample k (a table: the cost reads it
  /// m·L times per sample and evaluation, and working it out took two divisions each).
  int control(int k, int a) const { return ctrl[static_cast<std::size_t>(k) * m + a]; }
};

struct CostTerms {
  double h, h_min, h_max, lambda, mu, g;
  double clearance = 1e300;  ///< H: largest rise allowed within the block radius
};

/// Cost of the stack with control heights Z (layers × controls, row-major); if grad is
/// non-null, its gradient for the intermediate layers 1..N−1 ((N−1) × controls).
double printability_cost(const StackGrid& grid, const Eigen::MatrixXd& Z, const CostTerms& c,
                         Eigen::MatrixXd* grad);

/// The samples at `step` (mm) over hf's rectangle, on_patch where the raster's mask is set,
/// with hf's basis; without it when hf has no control points (hf's rectangle only).
void build_stack_grid(StackGrid& g, const HeightField& hf, double step,
                      const std::vector<char>& raster_mask, const Vec2& raster_origin,
                      double raster_cell, int raster_nx, int raster_ny);

}  // namespace nonplanar::layers
