// Stack construction plus optimisation for one 50 × 50 mm patch (issue 4 target: <= 0.5 s),
// one evaluation of its optimiser's cost and gradient, the normalisation of its mesh, a
// whole slice that prints as a shell, and the choice of a shell's print heights.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "layers/faceted_top.hpp"
#include "layers/patch_raster.hpp"
#include "layers/printability_cost.hpp"
#include "layers/shell_levels.hpp"
#include "nonplanar/deform.hpp"
#include "nonplanar/layers.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace {

struct Input {
  nonplanar::TriangleMesh mesh;
  nonplanar::Analysis analysis;
  std::vector<nonplanar::SurfaceFit> fits;
  std::vector<int> ids;
};

const Input& input() {
  static const Input in = [] {
    Input i;
    i.mesh = nonplanar::test::height_field_solid(
        [](double x, double y) { return 10 + 1.5 * std::sin(x / 8) * std::cos(y / 9); }, 0, 50, 0,
        50, 100, 100);
    i.analysis = *nonplanar::analyze(i.mesh, {}, {});
    i.fits.push_back(*nonplanar::fit_patch(i.mesh, i.analysis.patches[0], {}, {}));
    i.ids.push_back(0);
    return i;
  }();
  return in;
}

void BM_PlanLayers50mm(benchmark::State& state) {
  const Input& in = input();
  nonplanar::LayerParams p;
  for (auto _ : state) {
    auto plan = nonplanar::plan_layers(in.mesh, in.analysis, in.fits, in.ids, p, {});
    if (!plan || plan->stacks.size() != 1) return state.SkipWithError("no stack");
    state.counters["layers"] = plan->stacks[0].layers;
  }
}

// The stack optimiser's cost and gradient, as each of its iterations evaluates them: the
// patch's ~40 × 40 quadrature grid, 28 layers (the Prusa sphere's stack: 100 iterations),
// every term active (layers jittered out of the limits, a tight heater clearance).
void BM_PrintabilityCost(benchmark::State& state) {
  namespace layers = nonplanar::layers;
  const Input& in = input();
  const nonplanar::HeightField& top = in.fits[0].surface;
  const layers::PatchRaster r = layers::rasterize_patch(in.mesh, in.analysis.patches[0], 0.25, 0);
  layers::StackGrid g;
  layers::build_stack_grid(g, top, 50.0 / 40, r.mask, r.origin, r.cell, r.nx, r.ny);
  g.pair_within(6.0, 2.0);
  const int N = 27, nc = top.surface.n_u * top.surface.n_v;
  Eigen::MatrixXd Z(N + 1, nc);
  for (int i = 0; i <= N; ++i)
    for (int j = 0; j < nc; ++j)
      Z(i, j) = (1.0 - i / double(N)) * top.surface.points[j].z() + i / double(N) * 4.0 +
                (i > 0 && i < N ? 0.05 * std::sin(i * 7.0 + j) : 0.0);
  const layers::CostTerms terms{0.2, 0.105, 0.295, 0.05, 1e5, std::tan(0.5) - 0.01, 0.5};
  Eigen::MatrixXd grad;
  for (auto _ : state) benchmark::DoNotOptimize(layers::printability_cost(g, Z, terms, &grad));
  state.counters["samples"] = static_cast<double>(g.xy.size());
  state.counters["controls"] = nc;
}

void BM_NormalizeMesh50mm(benchmark::State& state) {
  const Input& in = input();
  auto plan = nonplanar::plan_layers(in.mesh, in.analysis, in.fits, in.ids, {}, {});
  for (auto _ : state) {
    auto n = nonplanar::normalize_mesh(in.mesh, *plan->field, {}, {});
    state.counters["triangles"] = static_cast<double>(n->mesh.faces.size());
  }
}

// The whole pipeline on an 80 mm wing rib whose top rises from 0.3 to 12.3 mm: no stack over
// a plane fits it, so it prints as a curved shell over a planar core (layers/shell_plan.hpp).
void BM_SliceRibShell(benchmark::State& state) {
  nonplanar::TriangleMesh mesh = nonplanar::test::rib();
  for (nonplanar::Vec3& v : mesh.vertices) v += nonplanar::Vec3(70, 104, 0);
  const nonplanar::SliceJob job = nonplanar::make_job({});
  for (auto _ : state) {
    auto r = nonplanar::slice_model(mesh, job, {});
    if (!r || r->shell_layers == 0) return state.SkipWithError("no shell");
    state.counters["layers"] = static_cast<double>(r->layers.size());
  }
}

// The stack's top on the facets (layers/faceted_top.hpp) for the 50 mm patch: a 0.1 mm
// raster over the patch and 8 mm around it (580 × 580 nodes), carried outward ring by ring
// and relaxed. It runs beside the fit, and was the longer of the two on the sine roof.
void BM_FacetedTop50mm(benchmark::State& state) {
  const Input& in = input();
  for (auto _ : state) {
    const auto t = nonplanar::layers::faceted_top(in.mesh, in.analysis.patches[0], 0.1, 8.0,
                                                  std::tan(0.8 * 45 * M_PI / 180) / M_SQRT2);
    state.counters["nodes"] = static_cast<double>(t.h.size());
  }
}

// The heights a shell beside a rim prints at (layers/shell_levels.hpp): 200 000 nodes of a
// 20 mm ramp, each printable up to 0.5 mm after its height, 8 levels over 1000 bins.
void BM_ChooseLevels(benchmark::State& state) {
  std::vector<double> u, lo, hi;
  for (int k = 0; k < 200000; ++k) {
    const double h = 20.0 * k / 199999;
    u.push_back(h), lo.push_back(h - 0.05), hi.push_back(h + 0.5);
  }
  for (auto _ : state) {
    const auto c = nonplanar::layers::choose_levels(u, lo, hi, 8);
    state.counters["banded"] = c.banded;
  }
}

BENCHMARK(BM_PlanLayers50mm)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PrintabilityCost)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_NormalizeMesh50mm)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SliceRibShell)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_ChooseLevels)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FacetedTop50mm)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
