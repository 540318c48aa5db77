#!/usr/bin/env bash
# Time `nonplanar slice` (--planar, the full non-planar pipeline, and that pipeline with
# PrusaSlicer as its engine, --engine prusaslicer) against
# `prusa-slicer --export-gcode` with equivalent settings on the same models, same machine,
# same run: the two in turn (nonplanar, PrusaSlicer, nonplanar, ...), the ratio taken pair by
# pair, so a drift of the shared machine's speed moves both halves of a pair alike. Prints the
# medians of wall time and peak memory and of the pairs' ratios (nonplanar / PrusaSlicer).
# Usage: bench/compare_prusa_slice.sh [RUNS=3] [MODEL...]
# Default models: Benchy and the bunny, the shared curved models (wing, FoilCutter, sphere,
# the CurviSlicer car and airfoil, the Voron ornament, the OpenSCAD heightmap),
# examples/wave_roof.stl (a wave tile) and four solids written by build/bench/make_test_solids
# (saddle, sine roof, dome cut by a box, a terrain tile). Installs prusa-slicer through scripts/setup.sh if
# needed, and builds.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
shift || true
models=("$@")
SETUP_ARGS=--with-prusaslicer bash scripts/build.sh >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if ((${#models[@]} == 0)); then
  ./build/bench/make_test_solids "$tmp/solids" >/dev/null
  s=../shared/models
  models=("$s"/gen_3DBenchy.stl "$s"/np_stanford_bunny_closed_compas.stl "$s"/np_curvislicer_wing.stl
          "$s"/np_curvislicer_FoilCutter.stl "$s"/np_prusa_sphere.stl "$s"/np_curvislicer_car_med.stl
          "$s"/np_curvislicer_airfoil.stl "$s"/np_voron_sphere_ornament_shellA.stl
          "$s"/np_openscad_example010_heightmap.stl examples/wave_roof.stl
          "$tmp"/solids/saddle.stl "$tmp"/solids/sine_roof.stl "$tmp"/solids/dome_cut_by_box.stl
          "$tmp"/solids/terrain_tile.stl)
fi

# The same print both ways: 0.2 mm layers, 2 perimeters, 5 top / 4 bottom solid layers,
# 20 % rectilinear infill, one skirt, 0.4 mm nozzle, 220 x 220 bed, Marlin 2.
common=(--layer-height 0.2 --first-layer-height 0.2 --perimeters 2 --top-solid-layers 5
        --bottom-solid-layers 4 --fill-density 20% --fill-pattern rectilinear --skirts 1
        --nozzle-diameter 0.4 --filament-diameter 1.75 --temperature 210 --bed-temperature 60)
run() {  # one whole-process run: "wall_s peak_KB"
  /usr/bin/time -o "$tmp/t" -f "%e %M" "$@" >/dev/null 2>&1 || { echo "error: failed: $*" >&2; exit 1; }
  cat "$tmp/t"
}
median() { sort -g | awk '{v[NR] = $1} END {print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
printf "%-36s %-10s %8s %8s %8s %8s %7s %7s\n" model mode "np s" "ps s" "np MB" "ps MB" "t ratio" "m ratio"
for m in "${models[@]}"; do
  ps=(prusa-slicer --export-gcode "${common[@]}" --gcode-flavor marlin2
      --bed-shape 0x0,220x0,220x220,0x220 --center 110,110 -o "$tmp/ps.gcode" "$m")
  for mode in planar non-planar engine; do
    flag=()
    [[ $mode == planar ]] && flag=(--planar)
    [[ $mode == engine ]] && flag=(--engine prusaslicer)
    np=(./build/nonplanar slice -q "$m" -o "$tmp/np.gcode" "${flag[@]}" "${common[@]}")
    run "${np[@]}" >/dev/null  # warm-up: the file cache, both programs
    run "${ps[@]}" >/dev/null
    : >"$tmp/pairs"
    for _ in $(seq "$runs"); do
      read -r nt nm < <(run "${np[@]}")
      read -r pt pm < <(run "${ps[@]}")
      echo "$nt $pt $nm $pm" >>"$tmp/pairs"
    done
    col() { awk -v c="$1" '{print $c}' "$tmp/pairs" | median; }
    tr=$(awk '{print ($2 > 0 ? $1 / $2 : 0)}' "$tmp/pairs" | median)
    mr=$(awk '{print ($4 > 0 ? $3 / $4 : 0)}' "$tmp/pairs" | median)
    awk -v n="$(basename "$m")" -v md="$mode" -v a="$(col 1)" -v b="$(col 2)" -v c="$(col 3)" \
      -v d="$(col 4)" -v t="$tr" -v r="$mr" \
      'BEGIN{printf "%-36s %-10s %8.2f %8.2f %8.1f %8.1f %7.2f %7.2f\n", n, md, a, b, c/1024, d/1024, t, r}'
  done
done
