// The whole non-planar slice (analysis, fit, stacks, field, normalisation, planar slice,
// toolpaths, map back, gate, G-code, stats) of two analytic solids, as `slice` runs it. #20's
// target is half PrusaSlicer's planar time on the same solid (bench/compare_prusa_slice.sh
// measures that ratio); this guards the stages' own cost.
#include <benchmark/benchmark.h>

#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace {

using namespace nonplanar;

void slice_it(benchmark::State& state, const TriangleMesh& raw) {
  const TriangleMesh mesh = test::placed(raw, PrintConfig{});
  const SliceJob job = make_job(PrintConfig{});
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto r = slice_model(mesh, job, {});
    if (!r || r->plan.stacks.empty()) state.SkipWithError("not sliced curved");
    bytes = r ? r->gcode.size() : 0;
  }
  state.counters["gcode_MB"] = static_cast<double>(bytes) / 1e6;
}

void BM_SliceSaddle(benchmark::State& state) {
  slice_it(state, test::saddle());
}
void BM_SliceDomeCutByBox(benchmark::State& state) {
  slice_it(state, test::dome_cut_by_box());
}
BENCHMARK(BM_SliceSaddle)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SliceDomeCutByBox)->Unit(benchmark::kMillisecond);

}  // namespace
