// check's figures (check.hpp) on a whole non-planar print: the thickness where layers cross,
// the deviation grid and the collision search over every extrusion point. Target: well under the
// slice that made the file (the 200 mm bunny's check took 53 s and 2.4 GB before the grid went
// dense, 13 s and 1.2 GB after; its slice takes about 7 s).
#include <benchmark/benchmark.h>

#include "nonplanar/check.hpp"
#include "nonplanar/pipeline.hpp"
#include "support/solids.hpp"

namespace {

using namespace nonplanar;

struct Sliced {
  TriangleMesh mesh;
  std::string gcode;
  std::vector<PrintMove> moves;
};

const Sliced& sine_roof() {
  static const Sliced s = [] {
    Sliced r;
    r.mesh = test::placed(test::sine_roof(), PrintConfig{});
    r.gcode = slice_model(r.mesh, make_job(PrintConfig{}), {})->gcode;
    r.moves = *read_gcode_moves(r.gcode);
    return r;
  }();
  return s;
}

void BM_CheckSineRoof(benchmark::State& state) {
  const Sliced& s = sine_roof();
  const CheckParams params = check_params(PrintConfig{}, 30);
  for (auto _ : state) benchmark::DoNotOptimize(check_print(s.moves, &s.mesh, params, {}));
  state.counters["moves"] = static_cast<double>(s.moves.size());
}
BENCHMARK(BM_CheckSineRoof)->Unit(benchmark::kMillisecond);

// The thickness where layers cross alone (LayerGaps), as check and the safety gate measure it
// (the gate on its second core). Target: a small part of the check above and of the sine
// roof's 0.35 s slice (about 0.04 s here when it was written; the bunny's 37 MB print, 0.7 s).
void BM_LayerGapsSineRoof(benchmark::State& state) {
  const Sliced& s = sine_roof();
  double least = 0;
  for (auto _ : state) {
    LayerGaps gaps;
    for (const PrintMove& m : s.moves) gaps.add(m);
    gaps.finish();
    least = gaps.min;
  }
  state.counters["thinnest_mm"] = least;
}
BENCHMARK(BM_LayerGapsSineRoof)->Unit(benchmark::kMillisecond);

}  // namespace
