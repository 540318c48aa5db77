// Stack construction plus optimisation for one 50 × 50 mm patch (issue 4 target: <= 0.5 s),
// the normalisation of its mesh, and a whole slice that prints as a shell.
#include <benchmark/benchmark.h>

#include <cmath>

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

BENCHMARK(BM_PlanLayers50mm)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_NormalizeMesh50mm)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_SliceRibShell)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
