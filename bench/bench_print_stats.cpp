// The stats pass every slice now ends with (gcode/print_stats.cpp): read the whole file, plan
// its time, rewrite its footer and M73s. Target: a small part of a planar slice's time (a
// planar Benchy, 24 MB of G-code, slices in 0.8 s here).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "nonplanar/gcode.hpp"
#include "nonplanar/program.hpp"
#include "program/gcode_text.hpp"

namespace {

// About 27 MB (the names say 10MB, which they were once): 200 layers of 4 000 short
// extrusions each, a travel between layers.
const std::string& gcode() {
  static const std::string text = [] {
    std::string s = "G90\nM83\n";
    char buf[96];
    for (int l = 0; l < 200; ++l) {
      std::snprintf(buf, sizeof buf, ";LAYER_CHANGE\n;Z:%.2f\nG1 Z%.2f F720\n", 0.2 * (l + 1),
                    0.2 * (l + 1));
      s += buf;
      for (int k = 0; k < 4000; ++k) {
        std::snprintf(buf, sizeof buf, "G1 X%.3f Y%.3f E0.0321 F%d\n",
                      100 + 20 * ((k / 100) % 2 ? 1 - (k % 100) / 100.0 : (k % 100) / 100.0),
                      100 + 0.45 * (k / 100), k % 100 == 0 ? 1800 : 2700);
        s += buf;
      }
    }
    return s + "; filament used [mm] = 0\n";
  }();
  return text;
}

void BM_PrintStats10MB(benchmark::State& state) {
  nonplanar::PrintConfig c;
  c.profile["remaining_times"] = "1";
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::with_print_stats(gcode(), c));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * gcode().size()));
}

}  // namespace

BENCHMARK(BM_PrintStats10MB)->Unit(benchmark::kMillisecond)->UseRealTime();

namespace {
void BM_ReadProgram10MB(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::read_gcode_program(gcode()));
}
void BM_EstimateTime10MB(benchmark::State& state) {
  const auto p = nonplanar::read_gcode_program(gcode());
  for (auto _ : state) benchmark::DoNotOptimize(nonplanar::estimate_print_time(p, {}));
}
}  // namespace
BENCHMARK(BM_ReadProgram10MB)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EstimateTime10MB)->Unit(benchmark::kMillisecond)->UseRealTime();

namespace {
// The gate's and check's reading: every move handed on, nothing kept (for_each_print_move).
// The gate reads its program this way four times (crossings, print time, the collision search's
// box and search): on the sine roof these readings were half of the gate's time.
void BM_ForEachPrintMove10MB(benchmark::State& state) {
  for (auto _ : state) {
    double e = 0;
    nonplanar::for_each_print_move(gcode(), {},
                                   [&](const nonplanar::PrintMove& m) { e += m.filament; });
    benchmark::DoNotOptimize(e);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * gcode().size()));
}
}  // namespace
BENCHMARK(BM_ForEachPrintMove10MB)->Unit(benchmark::kMillisecond)->UseRealTime();

namespace {
// The one writer's moves (program/gcode_text.hpp): a million "G1 X Y Z E" lines, coordinates
// over a 200 mm bed and E in relative mode, about 40 MB. 290 ms with to_chars for every
// number, 161 ms with gcode_text.cpp's integers where they are exact.
void BM_WriteMoves1M(benchmark::State& state) {
  std::vector<nonplanar::ProgramMove> moves(1000000);
  for (std::size_t k = 0; k < moves.size(); ++k) {
    auto& m = moves[k];
    const double u = static_cast<double>(k);
    m.to = {10 + 180 * std::fmod(u * 0.618034, 1.0), 10 + 180 * std::fmod(u * 0.414214, 1.0),
            0.2 + 0.0013 * static_cast<double>(k % 20000)};
    m.xy = m.z = true;
    m.de = 0.01 + 0.05 * std::fmod(u * 0.732051, 1.0);
  }
  std::size_t bytes = 0;
  for (auto _ : state) {
    nonplanar::program::GcodeText w(true);
    w.out.reserve(48 * moves.size());
    for (const auto& m : moves) w.move(m);
    bytes = w.out.size();
    benchmark::DoNotOptimize(w.out.data());
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
}
}  // namespace
BENCHMARK(BM_WriteMoves1M)->Unit(benchmark::kMillisecond)->UseRealTime();
