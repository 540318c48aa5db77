// Loading and analysing a 1.3M-triangle mesh. Target (issue 2): load + analyse <= 1.0 s on
// the 2-core reference machine.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "core/mesh_topology.hpp"
#include "dense_mesh.hpp"
#include "nonplanar/analysis.hpp"
#include "nonplanar/io.hpp"

namespace {

const std::filesystem::path& dense_file() {
  static const std::filesystem::path file = [] {
    auto p = std::filesystem::temp_directory_path() / "nonplanar_bench_dense.stl";
    if (!std::filesystem::exists(p)) {
      const std::string err = nonplanar::bench::write_dense_mesh(p);
      if (!err.empty()) throw std::runtime_error(err);
    }
    return p;
  }();
  return file;
}

void BM_Load(benchmark::State& state) {
  const auto& file = dense_file();
  for (auto _ : state) {
    auto m = nonplanar::load_mesh(file, {}, {});
    if (!m) state.SkipWithError(m.error().message.c_str());
    state.counters["triangles"] = static_cast<double>(m->mesh.faces.size());
  }
}

void BM_Analyze(benchmark::State& state) {
  auto m = nonplanar::load_mesh(dense_file(), {}, {});
  if (!m) return state.SkipWithError(m.error().message.c_str());
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::analyze(m->mesh, {}, {}));
}

void BM_Topology(benchmark::State& state) {
  auto m = nonplanar::load_mesh(dense_file(), {}, {});
  if (!m) return state.SkipWithError(m.error().message.c_str());
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::build_topology(m->mesh));
}

// One triangle 200k times over (hostile input #21.8: the per-vertex fan scan took 86 s on
// 96k copies; sorting half-edges is O(F log F)).
void BM_TopologyDuplicates(benchmark::State& state) {
  nonplanar::TriangleMesh m;
  m.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 5}};
  m.faces.assign(200000, {0, 1, 2});
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::build_topology(m));
}

void BM_LoadAndAnalyze(benchmark::State& state) {
  const auto& file = dense_file();
  for (auto _ : state) {
    auto m = nonplanar::load_mesh(file, {}, {});
    if (!m) return state.SkipWithError(m.error().message.c_str());
    benchmark::DoNotOptimize(nonplanar::analyze(m->mesh, {}, {}));
  }
}

BENCHMARK(BM_Load)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_Analyze)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);
BENCHMARK(BM_Topology)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TopologyDuplicates)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_LoadAndAnalyze)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
