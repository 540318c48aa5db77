// The slicer's own route (print_plan.hpp): reading a prepared part's plan, and post-process on
// a slicer's G-code of it. Targets: well under the slicer's own time for the part (PrusaSlicer
// slices the 24 mm dome in about 0.4 s here; on the 200 mm bunny's 14.7 MB of G-code,
// post-process took 2.5 s against PrusaSlicer's 5.3 s to slice it).
#include <benchmark/benchmark.h>

#include "nonplanar/field_io.hpp"
#include "nonplanar/print_plan.hpp"
#include "support/solids.hpp"

namespace {

using namespace nonplanar;

struct Prepared {
  PreparedPart part;
  std::string gcode;  // our planar engine's G-code of the normalised part, as a slicer's
};

const Prepared& dome() {
  static const Prepared p = [] {
    Prepared d;
    const TriangleMesh mesh = test::placed(test::dome_cut_by_box(), PrintConfig{});
    d.part = *prepare_part(mesh, make_job(PrintConfig{}), {});
    SliceJob job = make_job(PrintConfig{});
    job.planar_only = true;
    d.gcode = slice_model(d.part.normalized, job, {})->gcode +
              "; prusaslicer_config = begin\n; layer_height = 0.2\n; first_layer_height = "
              "0.2\n; prusaslicer_config = end\n";
    return d;
  }();
  return p;
}

void BM_ReadPlan(benchmark::State& state) {
  const std::string text = plan_json(dome().part.plan);
  for (auto _ : state) {
    auto plan = parse_plan_json(text);
    benchmark::DoNotOptimize(parse_layer_field_json(plan->field));
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
}
BENCHMARK(BM_ReadPlan)->Unit(benchmark::kMillisecond);

void BM_PostProcessDome(benchmark::State& state) {
  const Prepared& d = dome();
  for (auto _ : state) benchmark::DoNotOptimize(post_process_gcode(d.gcode, d.part.plan, {}));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * d.gcode.size()));
}
BENCHMARK(BM_PostProcessDome)->Unit(benchmark::kMillisecond);

}  // namespace
