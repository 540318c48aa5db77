// Fitting a sine height field (60 × 60 mm, amplitude 1.5 mm, wavelengths 25 and 30 mm) to
// 0.005 mm. Target (issue 3): 100k samples <= 0.3 s; time should grow about linearly with
// the sample count. "Linear" is the polynomial fit with knot refinement; "Default" is the
// default pipeline (which stops there when the tolerance is met); "Full" always adds free
// weights and Levenberg–Marquardt.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "nonplanar/patch_fit.hpp"

namespace {

std::vector<nonplanar::Vec3> sine_samples(std::size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(0, 60);
  std::vector<nonplanar::Vec3> s(n);
  for (auto& p : s) {
    const double x = d(rng), y = d(rng);
    p = {x, y, 5 + 1.5 * std::sin(2 * M_PI * x / 25) * std::cos(2 * M_PI * y / 30)};
  }
  return s;
}

void run(benchmark::State& state, const nonplanar::FitParams& params) {
  const auto samples = sine_samples(static_cast<std::size_t>(state.range(0)));
  double rms = 0;
  int grid = 0;
  for (auto _ : state) {
    auto fit = nonplanar::fit_height_field(samples, {0, 0}, {60, 60}, 0.5, params, {});
    if (!fit) return state.SkipWithError(fit.error().message.c_str());
    rms = fit->rms_error;
    grid = fit->surface.surface.n_u;
  }
  state.counters["rms_mm"] = rms;
  state.counters["grid"] = grid;
  state.SetComplexityN(state.range(0));
}

void BM_FitLinear(benchmark::State& state) {
  nonplanar::FitParams p;
  p.free_weights = false;
  p.nonlinear = nonplanar::NonlinearSolver::none;
  run(state, p);
}

// The default pipeline: stops after the linear fit when that meets the tolerance.
void BM_FitDefault(benchmark::State& state) {
  run(state, {});
}

void BM_FitFull(benchmark::State& state) {
  nonplanar::FitParams p;
  p.refine_only_if_needed = false;
  run(state, p);
}

BENCHMARK(BM_FitLinear)
    ->RangeMultiplier(2)
    ->Range(25000, 200000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Complexity(benchmark::oN);
BENCHMARK(BM_FitDefault)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FitFull)
    ->RangeMultiplier(2)
    ->Range(25000, 200000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Complexity(benchmark::oN);

}  // namespace
