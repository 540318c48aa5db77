// Stage nurbs, fitting (paper §3–4; DESIGN.md §2 step 3): one height-field NURBS surface per
// patch, z = S(u(x), v(y)), by linear least squares with a thin-plate term, adaptive knot
// refinement, then (optionally) free weights by the linearised rational fit and a nonlinear
// Gauss–Newton / Levenberg–Marquardt refinement.
#pragma once

#include <string>
#include <vector>

#include "nonplanar/context.hpp"
#include "nonplanar/mesh.hpp"
#include "nonplanar/nurbs.hpp"
#include "nonplanar/status.hpp"

namespace nonplanar {

/// Which nonlinear method refines control heights and weights after the linear fits.
enum class NonlinearSolver {
  none,                      ///< stop after the linear (and linearised rational) fits
  levenberg_marquardt,       ///< Ceres trust region, weights bounded by simple bounds
  gauss_newton_line_search,  ///< Gauss–Newton with Armijo backtracking; weights bounded by
                             ///< the substitution w = w_min + (w_max − w_min)(1 + tanh t)/2
};
const char* solver_name(NonlinearSolver s);

/// Inputs of the fit. Millimetres.
struct FitParams {
  double tolerance = 0.005;     ///< fit_tolerance: target RMS (max target is 4×), mm
  double sample_density = 4.0;  ///< data samples per mm² on the patch's triangles (+ vertices)
  double margin = 0.05;         ///< footprint grown by this fraction each side (≥ 0.5 mm)
  int degree = 3;
  int initial_spans = 4;     ///< per direction, before refinement
  int max_control = 48;      ///< control points per direction at most
  double smoothing = 1e-4;   ///< thin-plate weight (mm⁴) times the sample density
  bool free_weights = true;  ///< fit weights too (rational); false keeps w = 1
  NonlinearSolver nonlinear = NonlinearSolver::levenberg_marquardt;
  /// Run the rational and nonlinear steps only when the polynomial fit misses the targets
  /// (they cost ~10× the linear fit); false runs them always, to squeeze the error further.
  bool refine_only_if_needed = true;
  double weight_min = 0.2, weight_max = 5.0;  ///< bounds on the weights
  int max_iterations = 50;                    ///< of the nonlinear solver
};

/// What the nonlinear solver did.
struct NonlinearReport {
  NonlinearSolver solver = NonlinearSolver::none;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;  ///< ½ Σ r², mm²
  std::string termination;                  ///< why it stopped
};

/// One fitted surface with its quality figures.
struct SurfaceFit {
  HeightField surface;
  std::size_t samples = 0;              ///< data points used
  int refinements = 0;                  ///< knot-insertion rounds
  double linear_rms = 0;                ///< RMS of the polynomial fit at the final grid, mm
  double rms_error = 0, max_error = 0;  ///< at the data samples, mm
  NonlinearReport nonlinear;
  double seconds = 0;
};

/// The rectangle fit_height_field fits a surface over: [xy_min, xy_max] grown on each side by
/// `margin` of its size, at least 0.5 mm. Output: a HeightField with that origin and extent
/// (mm) and no control points yet (plan_layers' stack checks that need no surface use it).
HeightField fit_rectangle(const Vec2& xy_min, const Vec2& xy_max, double margin);

/// Fit z = S(x, y) to scattered samples (x, y, z) over the rectangle [xy_min, xy_max] (grown
/// by the margin). `min_span` (mm) stops refinement below that knot spacing, so a faceted
/// mesh is not fitted facet by facet. Errors: invalid_argument (naming the parameter, or
/// fewer samples than needed), cancelled.
Expected<SurfaceFit> fit_height_field(const std::vector<Vec3>& samples, const Vec2& xy_min,
                                      const Vec2& xy_max, double min_span, const FitParams& params,
                                      const Context& ctx);

}  // namespace nonplanar
