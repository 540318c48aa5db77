// Internals of the height-field fit shared by the linear and nonlinear steps.
//
// Notation: samples in parameter space t_k = (u_k, v_k, z_k); for the current knots each
// sample lies in span (su_k, sv_k) with basis values Nu_k[0..p], Nv_k[0..q]; D_k = Σ N w is
// the rational denominator; S_k = Σ N w z / D_k the surface height; r_k = S_k − z_k.
#pragma once

#include "nonplanar/context.hpp"

#include <vector>

#include "nonplanar/fit.hpp"

namespace nonplanar::nurbs {

/// Per-sample span and basis values for the current knots of `s`.
struct SampleBasis {
  std::vector<int> su, sv;
  std::vector<double> nu, nv;  ///< (p+1) and (q+1) values per sample
  void compute(const NurbsSurface& s, const std::vector<Vec3>& uvz);
};

/// Height of sample k from its stored basis (z of the rational surface); *denominator, if
/// given, gets D_k = Σ N w.
double sample_height(const NurbsSurface& s, const SampleBasis& b, int k,
                     double* denominator = nullptr);

/// Residuals r_k = S_k − z_k; returns RMS, *max gets max |r|.
double residuals(const NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                 std::vector<double>* r, double* max);

/// Polynomial least squares (all weights 1): heights z_ij minimising Σ r² + λ·thin plate.
/// sx, sy: footprint size (mm), for the thin plate in physical units.
bool fit_polynomial(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                    double lambda, double sx, double sy);

/// The paper's linear form for free weights: unknowns a_ij = w_ij z_ij and w_ij with
/// Σ N (a − z_k w) ≈ 0 per sample, each row divided by the previous denominator D_k so it
/// approximates r_k, iterated while the RMS improves by > 1 %. Weights are normalised to
/// mean 1 and clamped to [w_min, w_max]. Returns the final RMS.
double fit_rational_linearised(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                               double lambda, double sx, double sy, const FitParams& params);

/// Nonlinear refinement over heights (and weights when params.free_weights) of the data
/// residuals plus regularisation: second differences of the heights (weight `lambda`) and
/// a pull of the weights towards 1.
/// Reports progress as "fit" from 0.8 to 1 and stops early when ctx is cancelled.
NonlinearReport fit_nonlinear(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                              double lambda, const FitParams& params, const Context& ctx);

}  // namespace nonplanar::nurbs
