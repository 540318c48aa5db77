#!/usr/bin/env bash
# Time `nonplanar slice` (both --planar and the full non-planar pipeline) against
# `prusa-slicer --export-gcode` with equivalent settings on the same models, same machine,
# same run; print wall time, peak memory and the ratios to PrusaSlicer.
# Usage: bench/compare_prusa_slice.sh [RUNS=3] [MODEL...]
# Default models: Benchy and the bunny (issue 5), the wing, FoilCutter and sphere (curved
# tops) from ../shared/models, and examples/wave_roof.stl. Installs prusa-slicer through
# scripts/setup.sh if needed, and builds.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
shift || true
models=("$@")
if ((${#models[@]} == 0)); then
  models=(../shared/models/gen_3DBenchy.stl ../shared/models/np_stanford_bunny_closed_compas.stl
          ../shared/models/np_curvislicer_wing.stl ../shared/models/np_curvislicer_FoilCutter.stl
          ../shared/models/np_prusa_sphere.stl examples/wave_roof.stl)
fi
SETUP_ARGS=--with-prusaslicer bash scripts/build.sh >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# The same print both ways: 0.2 mm layers, 2 perimeters, 5 top / 4 bottom solid layers,
# 20 % rectilinear infill, one skirt, 0.4 mm nozzle, 220 x 220 bed, Marlin 2.
common=(--layer-height 0.2 --first-layer-height 0.2 --perimeters 2 --top-solid-layers 5
        --bottom-solid-layers 4 --fill-density 20% --fill-pattern rectilinear --skirts 1
        --nozzle-diameter 0.4 --filament-diameter 1.75 --temperature 210 --bed-temperature 60)
best() {  # best-of-N wall time (s) and that run's peak RSS (KB)
  local bt=999999 bm=0 t m
  for _ in $(seq "$runs"); do
    /usr/bin/time -o "$tmp/t" -f "%e %M" "$@" >/dev/null 2>&1 || { echo "error: failed: $*" >&2; exit 1; }
    read -r t m <"$tmp/t"
    if awk -v a="$t" -v b="$bt" 'BEGIN{exit !(a<b)}'; then bt=$t bm=$m; fi
  done
  echo "$bt $bm"
}
printf "%-36s %-10s %8s %8s %8s %8s %7s %7s\n" model mode "np s" "ps s" "np MB" "ps MB" "t ratio" "m ratio"
for m in "${models[@]}"; do
  read -r pt pm < <(best prusa-slicer --export-gcode "${common[@]}" --gcode-flavor marlin2 \
    --bed-shape 0x0,220x0,220x220,0x220 --center 110,110 -o "$tmp/ps.gcode" "$m")
  modes=(planar non-planar)
  # The 200 mm bunny's non-planar slice takes minutes today; time it on request only.
  [[ $(basename "$m") == np_stanford_bunny_closed_compas.stl && -z "${BUNNY_NONPLANAR:-}" ]] && modes=(planar)
  for mode in "${modes[@]}"; do
    flag=()
    [[ $mode == planar ]] && flag=(--planar)
    read -r nt nm < <(best ./build/nonplanar slice -q "$m" -o "$tmp/np.gcode" "${flag[@]}" "${common[@]}")
    awk -v n="$(basename "$m")" -v md="$mode" -v a="$nt" -v b="$pt" -v c="$nm" -v d="$pm" \
      'BEGIN{printf "%-36s %-10s %8.2f %8.2f %8.1f %8.1f %7.2f %7.2f\n", n, md, a, b, c/1024, d/1024, a/b, c/d}'
  done
done
