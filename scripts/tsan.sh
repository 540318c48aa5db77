#!/usr/bin/env bash
# The test suite under ThreadSanitizer, built with clang-14 into build-tsan/: the pipeline's
# stages run tbb::parallel_for (layers, slicing, toolpaths, deform, analysis), and a data race
# there would print differently from run to run. Any report fails the test that triggered it.
# TBB is Debian's uninstrumented build, so under TSan the loops run on plain std::threads
# (src/core/parallel.hpp) and TSan sees every synchronisation; scripts/tsan.supp holds what is
# suppressed in libraries we do not build (nothing, so far).
# Usage: scripts/tsan.sh [CTEST_REGEX]   (default: every test)
# Environment: BUILD_DIR (default build-tsan); CI=true turns warnings into errors.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --with-clang
build_dir=${BUILD_DIR:-build-tsan}
werror=OFF
[[ "${CI:-}" == "true" ]] && werror=ON
generator=()
command -v ninja >/dev/null && [[ ! -f "$build_dir/CMakeCache.txt" ]] && generator=(-G Ninja)
# Line tables only, as scripts/sanitize.sh: a report needs no more, and it compiles faster.
CXX=clang++-14 cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -gline-tables-only -DNDEBUG" -DNONPLANAR_TSAN=ON \
  -DNONPLANAR_BUILD_BENCH=OFF -DNONPLANAR_WERROR="$werror" >/dev/null
jobs=$(nproc)  # before OMP_NUM_THREADS is set below: GNU nproc obeys it
cmake --build "$build_dir" -j"$jobs"
# Ceres' sparse solves reach CHOLMOD and OpenBLAS, which run OpenMP threads whose runtime is
# not instrumented either: as few of them as can be (one), and what libgomp still does is
# suppressed (scripts/tsan.supp), so every report is about our own threads.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/scripts/tsan.supp}
cd "$build_dir"
# Left out here (scripts/test.sh and scripts/sanitize.sh run them): tests whose time is
# another program's (PrusaSlicer slicing stock presets or a prepared part, Chromium drawing the
# preview); the threaded stages they reach are run under TSan by the slice and engine tests.
# The bunny's four shells take 3.5 minutes here (and leave ASan's run too); the threads they
# reach are the ones the other shell tests run. The head options' CLI runs (CliToolhead, 33 s
# of this suite's 385 s) stay out too: they slice the solids the NonplanarPrint tests slice.
ctest --output-on-failure -j"$jobs" --timeout 1800 ${1:+-R "$1"} \
  -E '^(NonplanarPrint\.SharedBunny|Preview\.TheBrowser|StockPresets\.(CurvedTops|TheWing)|PostProcessRoute\.|CliToolhead\.)'

