// check's figures (check.hpp) on a whole non-planar print: the thickness and deviation grid
// and the collision search over every extrusion point. Target: well under the slice that
// made the file (the 200 mm bunny's check took 53 s and 2.4 GB before the grid went dense,
// 13 s and 1.2 GB after; its slice takes about 7 s).
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

}  // namespace
