// Nonlinear refinement of heights and weights (paper §4): Levenberg–Marquardt through Ceres
// with simple bounds on the weights, or Gauss–Newton with an Armijo line search where the
// bounds come from a variable substitution.
//
// Notation: for sample k, D = Σ N_ij w_ij, S = Σ N_ij w_ij z_ij / D, r = S − z_k;
// ∂r/∂z_ij = N_ij w_ij / D, ∂r/∂w_ij = N_ij (z_ij − S) / D. Regularisation: √λ times the
// second differences of z along i and j; √γ (w_ij − 1).
#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>

#include "nurbs/fit_internal.hpp"
#include "nurbs/grid_normal_equations.hpp"
#include "nurbs/solver_callbacks.hpp"

namespace nonplanar {

const char* solver_name(NonlinearSolver s) {
  switch (s) {
    case NonlinearSolver::none:
      return "none";
    case NonlinearSolver::levenberg_marquardt:
      return "levenberg-marquardt";
    case NonlinearSolver::gauss_newton_line_search:
      return "gauss-newton-line-search";
  }
  return "unknown";
}

namespace nurbs {
namespace {

struct Regularisation {
  double lambda_sd;  // second differences of z
  double gamma;      // weights towards 1
};

Regularisation regularisation(const NurbsSurface& s, std::size_t samples, double lambda) {
  const double n = static_cast<double>(s.n_u) * s.n_v;
  return {lambda * 1e-3, 1e-4 * static_cast<double>(samples) / n};
}

// All samples of one knot span: residuals over the span's (p+1)(q+1) control points, each a
// parameter block [z] or [z, w].
class SpanCost : public ceres::CostFunction {
 public:
  SpanCost(const NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
           std::vector<int> samples, bool free_w)
      : s_(s), b_(b), uvz_(uvz), samples_(std::move(samples)), free_w_(free_w) {
    set_num_residuals(static_cast<int>(samples_.size()));
    for (int i = 0; i < (s.p + 1) * (s.q + 1); ++i)
      mutable_parameter_block_sizes()->push_back(free_w ? 2 : 1);
  }
  bool Evaluate(double const* const* x, double* residuals, double** jac) const override {
    const int mu = s_.p + 1, mv = s_.q + 1, m = mu * mv;
    for (std::size_t r = 0; r < samples_.size(); ++r) {
      const int k = samples_[r];
      const int i0 = b_.su[k] - s_.p, j0 = b_.sv[k] - s_.q;
      double num = 0, den = 0;
      for (int a = 0; a < mu; ++a)
        for (int c = 0; c < mv; ++c) {
          const int blk = a * mv + c;
          const double w = free_w_ ? x[blk][1] : s_.w(i0 + a, j0 + c);
          const double nw = b_.nu[k * mu + a] * b_.nv[k * mv + c] * w;
          num += nw * x[blk][0];
          den += nw;
        }
      const double S = num / den;
      residuals[r] = S - uvz_[k].z();
      if (!jac) continue;
      for (int blk = 0; blk < m; ++blk) {
        if (!jac[blk]) continue;
        const int a = blk / mv, c = blk % mv;
        const double nn = b_.nu[k * mu + a] * b_.nv[k * mv + c];
        const double w = free_w_ ? x[blk][1] : s_.w(i0 + a, j0 + c);
        const int bs = free_w_ ? 2 : 1;
        jac[blk][r * bs] = nn * w / den;
        if (free_w_) jac[blk][r * bs + 1] = nn * (x[blk][0] - S) / den;
      }
    }
    return true;
  }

 private:
  const NurbsSurface& s_;
  const SampleBasis& b_;
  const std::vector<Vec3>& uvz_;
  std::vector<int> samples_;
  bool free_w_;
};

// √λ (z_a − 2 z_b + z_c) over three parameter blocks (z first in each).
struct SecondDifference {
  double sqrt_lambda;
  template <class T>
  bool operator()(const T* a, const T* b, const T* c, T* r) const {
    r[0] = T(sqrt_lambda) * (a[0] - T(2) * b[0] + c[0]);
    return true;
  }
};

struct WeightPrior {
  double sqrt_gamma;
  template <class T>
  bool operator()(const T* zw, T* r) const {
    r[0] = T(sqrt_gamma) * (zw[1] - T(1));
    return true;
  }
};

NonlinearReport levenberg_marquardt(const Context& ctx, NurbsSurface& s, const SampleBasis& b,
                                    const std::vector<Vec3>& uvz, const Regularisation& reg,
                                    const FitParams& params) {
  const bool free_w = params.free_weights;
  const int bs = free_w ? 2 : 1;
  const int n = s.n_u * s.n_v;
  std::vector<double> x(static_cast<std::size_t>(n) * bs);
  for (int i = 0; i < n; ++i) {
    x[i * bs] = s.points[i].z();
    if (free_w) x[i * bs + 1] = s.weights[i];
  }
  auto block = [&](int i, int j) { return &x[static_cast<std::size_t>(i * s.n_v + j) * bs]; };
  ceres::Problem::Options popts;
  popts.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(popts);
  // Group samples by span.
  std::vector<std::vector<int>> by_span(static_cast<std::size_t>(s.n_u) * s.n_v);
  for (std::size_t k = 0; k < uvz.size(); ++k)
    by_span[static_cast<std::size_t>(b.su[k]) * s.n_v + b.sv[k]].push_back(static_cast<int>(k));
  for (int su = s.p; su < s.n_u; ++su)
    for (int sv = s.q; sv < s.n_v; ++sv) {
      auto& list = by_span[static_cast<std::size_t>(su) * s.n_v + sv];
      if (list.empty()) continue;
      std::vector<double*> blocks;
      for (int a = 0; a <= s.p; ++a)
        for (int c = 0; c <= s.q; ++c) blocks.push_back(block(su - s.p + a, sv - s.q + c));
      problem.AddResidualBlock(new SpanCost(s, b, uvz, std::move(list), free_w), nullptr, blocks);
    }
  const double sl = std::sqrt(reg.lambda_sd);
  auto difference = [&](double* z0, double* z1, double* z2) {
    // The term reads z only, but Ceres needs the blocks' real sizes.
    ceres::CostFunction* f =
        free_w ? static_cast<ceres::CostFunction*>(
                     new ceres::AutoDiffCostFunction<SecondDifference, 1, 2, 2, 2>(
                         new SecondDifference{sl}))
               : new ceres::AutoDiffCostFunction<SecondDifference, 1, 1, 1, 1>(
                     new SecondDifference{sl});
    problem.AddResidualBlock(f, nullptr, z0, z1, z2);
  };
  for (int i = 0; i < s.n_u; ++i)
    for (int j = 0; j < s.n_v; ++j) {
      if (i > 0 && i + 1 < s.n_u) difference(block(i - 1, j), block(i, j), block(i + 1, j));
      if (j > 0 && j + 1 < s.n_v) difference(block(i, j - 1), block(i, j), block(i, j + 1));
    }
  if (free_w) {
    for (int i = 0; i < n; ++i) {
      double* blk = &x[static_cast<std::size_t>(i) * 2];
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<WeightPrior, 1, 2>(new WeightPrior{std::sqrt(reg.gamma)}),
          nullptr, blk);
      problem.SetParameterLowerBound(blk, 1, params.weight_min);
      problem.SetParameterUpperBound(blk, 1, params.weight_max);
    }
  }
  // Ceres requires 2D blocks that appear only in bound calls to be in the problem already;
  // every block is in some span cost or difference term when the grid has data.
  ceres::Solver::Options opts;
  opts.minimizer_type = ceres::TRUST_REGION;
  opts.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  opts.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  // Eigen's simplicial Cholesky, not SuiteSparse's: these systems are small (the CurviSlicer
  // car's roof, 1254 unknowns) and CHOLMOD's supernodal factorisation spent its time in
  // ATLAS and OpenMP start-up and spinning: the car roof's 44 steps took 0.41 s against
  // 0.27 s, to the same final cost.
  opts.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  opts.max_num_iterations = params.max_iterations;
  opts.num_threads = 2;
  opts.logging_type = ceres::SILENT;
  // Stop when an iteration gains less than 0.01 % of the cost: on FoilCutter the last 41 of
  // 50 iterations (0.18 s) moved the RMS by 0.04 µm.
  opts.function_tolerance = 1e-4;
  SolverProgress progress(ctx, "fit", 0.8, 1.0, params.max_iterations);
  opts.callbacks.push_back(&progress);
  ceres::Solver::Summary summary;
  ceres::Solve(opts, &problem, &summary);
  NonlinearReport rep;
  rep.solver = NonlinearSolver::levenberg_marquardt;
  rep.iterations = static_cast<int>(summary.iterations.size()) - 1;
  rep.initial_cost = summary.initial_cost;
  rep.final_cost = summary.final_cost;
  rep.termination = std::string(ceres::TerminationTypeToString(summary.termination_type)) + ": " +
                    summary.message;
  if (summary.IsSolutionUsable() && summary.final_cost <= summary.initial_cost)
    for (int i = 0; i < n; ++i) {
      s.points[i].z() = x[i * bs];
      if (free_w) s.weights[i] = x[i * bs + 1];
    }
  return rep;
}

// Objective of the Gauss–Newton solver: ½ Σ r² over data and regularisation.
double gn_cost(const NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
               const Regularisation& reg, bool free_w) {
  std::vector<double> r;
  double c = 0;
  residuals(s, b, uvz, &r, nullptr);
  for (double v : r) c += v * v;
  for (int i = 0; i < s.n_u; ++i)
    for (int j = 0; j < s.n_v; ++j) {
      if (i > 0 && i + 1 < s.n_u) {
        const double d = s.P(i - 1, j).z() - 2 * s.P(i, j).z() + s.P(i + 1, j).z();
        c += reg.lambda_sd * d * d;
      }
      if (j > 0 && j + 1 < s.n_v) {
        const double d = s.P(i, j - 1).z() - 2 * s.P(i, j).z() + s.P(i, j + 1).z();
        c += reg.lambda_sd * d * d;
      }
      if (free_w) c += reg.gamma * (s.w(i, j) - 1) * (s.w(i, j) - 1);
    }
  return 0.5 * c;
}

NonlinearReport gauss_newton(const Context& ctx, NurbsSurface& s, const SampleBasis& b,
                             const std::vector<Vec3>& uvz, const Regularisation& reg,
                             const FitParams& params) {
  const bool free_w = params.free_weights;
  const int mu = s.p + 1, mv = s.q + 1, n = s.n_u * s.n_v;
  const double lo = params.weight_min, span = params.weight_max - params.weight_min;
  // w = lo + span (1 + tanh t) / 2; start from t matching the current weights.
  std::vector<double> t(n);
  for (int i = 0; i < n; ++i)
    t[i] = std::atanh(std::clamp(2 * (s.weights[i] - lo) / span - 1, -0.999999, 0.999999));
  auto set_weights = [&](NurbsSurface& dst, const std::vector<double>& tt) {
    for (int i = 0; i < n; ++i) dst.weights[i] = lo + 0.5 * span * (1 + std::tanh(tt[i]));
  };
  if (free_w) set_weights(s, t);
  NonlinearReport rep;
  rep.solver = NonlinearSolver::gauss_newton_line_search;
  double cost = gn_cost(s, b, uvz, reg, free_w);
  rep.initial_cost = cost;
  rep.termination = "max iterations";
  std::vector<double> cz(static_cast<std::size_t>(mu) * mv), cw(cz.size());
  const double* rows[2] = {cz.data(), cw.data()};
  // Second-difference taps (1, −2, 1) along i and along j, laid out like a span's
  // coefficients; the row scale √λ is applied by add_row. They touch the z block only.
  const double sl = std::sqrt(reg.lambda_sd), sg = std::sqrt(reg.gamma);
  std::vector<double> taps_i(static_cast<std::size_t>(mu) * mv, 0.0), taps_j(taps_i.size(), 0.0);
  const std::vector<double> zeros(taps_i.size(), 0.0);
  for (int a = 0; a < 3 && a < mu; ++a) taps_i[a * mv] = a == 1 ? -2 : 1;
  for (int c = 0; c < 3 && c < mv; ++c) taps_j[c] = c == 1 ? -2 : 1;
  const double* along_i[2] = {taps_i.data(), zeros.data()};
  const double* along_j[2] = {taps_j.data(), zeros.data()};
  for (int it = 0; it < params.max_iterations; ++it) {
    ctx.progress("fit", 0.8 + 0.2 * it / params.max_iterations);
    if (ctx.cancelled()) {
      rep.termination = "cancelled";
      break;
    }
    GridNormalEquations ne(s.n_u, s.n_v, s.p, s.q, free_w ? 2 : 1);
    for (std::size_t k = 0; k < uvz.size(); ++k) {
      const int i0 = b.su[k] - s.p, j0 = b.sv[k] - s.q;
      double den = 0;
      const double S = sample_height(s, b, static_cast<int>(k), &den), r = S - uvz[k].z();
      for (int a = 0; a < mu; ++a)
        for (int c = 0; c < mv; ++c) {
          const std::size_t idx = static_cast<std::size_t>(i0 + a) * s.n_v + (j0 + c);
          const double nn = b.nu[k * mu + a] * b.nv[k * mv + c];
          cz[a * mv + c] = nn * s.weights[idx] / den;
          const double dwdt = 0.5 * span * (1 - std::pow(std::tanh(t[idx]), 2));
          cw[a * mv + c] = nn * (s.points[idx].z() - S) / den * dwdt;
        }
      ne.add_row(i0, j0, rows, -r);  // JᵀJ δ = −Jᵀr
    }
    // Regularisation rows: second differences along i and j (z block only), weight prior.
    for (int i = 0; i < s.n_u; ++i)
      for (int j = 0; j < s.n_v; ++j) {
        if (i > 0 && i + 1 < s.n_u && mu >= 3)
          ne.add_row(i - 1, j, along_i,
                     -(s.P(i - 1, j).z() - 2 * s.P(i, j).z() + s.P(i + 1, j).z()), sl);
        if (j > 0 && j + 1 < s.n_v && mv >= 3)
          ne.add_row(i, j - 1, along_j,
                     -(s.P(i, j - 1).z() - 2 * s.P(i, j).z() + s.P(i, j + 1).z()), sl);
        if (free_w) {
          const int idx = i * s.n_v + j;
          const double dwdt = 0.5 * span * (1 - std::pow(std::tanh(t[idx]), 2));
          ne.add_entry(1, idx, sg * dwdt, -sg * (s.weights[idx] - 1));
        }
      }
    ne.add_diagonal(1e-12, 0);
    if (free_w) ne.add_diagonal(1e-12, 1);
    Eigen::VectorXd delta;
    if (!ne.solve(&delta)) {
      rep.termination = "normal equations not positive definite";
      break;
    }
    // Backtracking: halve the step until the Armijo condition holds, f(x + αδ) ≤ f(x) +
    // 1e-4 α ∇fᵀδ with ∇fᵀδ = (Jᵀr)ᵀδ = −rhsᵀδ.
    const double predicted = ne.rhs().dot(delta);
    if (!(predicted > 0)) {
      rep.termination = "converged: no descent direction";
      break;
    }
    double alpha = 1.0;
    bool accepted = false;
    NurbsSurface trial = s;
    std::vector<double> tt = t;
    for (int ls = 0; ls < 30; ++ls, alpha *= 0.5) {
      for (int i = 0; i < n; ++i) trial.points[i].z() = s.points[i].z() + alpha * delta[i];
      if (free_w) {
        for (int i = 0; i < n; ++i) tt[i] = t[i] + alpha * delta[n + i];
        set_weights(trial, tt);
      }
      const double c = gn_cost(trial, b, uvz, reg, free_w);
      if (c <= cost - 1e-4 * alpha * predicted) {
        accepted = true;
        const double rel = (cost - c) / std::max(cost, 1e-300);
        s = trial;
        t = tt;
        cost = c;
        rep.iterations = it + 1;
        if (rel < 1e-9) {
          rep.termination = "converged: relative decrease below 1e-9";
          it = params.max_iterations;
        }
        break;
      }
    }
    if (!accepted) {
      rep.termination = "converged: no decrease along the Gauss-Newton direction";
      break;
    }
  }
  rep.final_cost = cost;
  return rep;
}

}  // namespace

NonlinearReport fit_nonlinear(NurbsSurface& s, const SampleBasis& b, const std::vector<Vec3>& uvz,
                              double lambda, const FitParams& params, const Context& ctx) {
  const Regularisation reg = regularisation(s, uvz.size(), lambda);
  switch (params.nonlinear) {
    case NonlinearSolver::levenberg_marquardt:
      return levenberg_marquardt(ctx, s, b, uvz, reg, params);
    case NonlinearSolver::gauss_newton_line_search:
      return gauss_newton(ctx, s, b, uvz, reg, params);
    case NonlinearSolver::none:
      break;
  }
  return {};
}

}  // namespace nurbs
}  // namespace nonplanar
