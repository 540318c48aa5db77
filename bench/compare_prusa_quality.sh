#!/usr/bin/env bash
# The quality figures of DESIGN.md §4 for nonplanar's non-planar slice and PrusaSlicer's
# planar one, side by side, measured by `nonplanar check` on both G-code files.
# Usage: bench/compare_prusa_quality.sh [MODEL...]
# Default models: the end-to-end and coverage issues' analytic solids (written by build/bench/
# make_test_solids: among them #19's hollow shells, tall reliefs, a mouse's shell, a top over a
# pocket, a top partly under another, a CAD block's fillets and a terrain tile), the shared curved models (wing, FoilCutter, sphere),
# examples/wave_roof.stl and seven shared real parts (ankle base, car, airfoil, the Voron
# ornament, the OpenSCAD heightmap, Benchy, the Slic3r spiky block; give the bunny by name: it
# takes a minute). Same
# print both ways: 0.2 mm layers, 0.4 mm nozzle, max_angle 30°. The last line counts the
# shared models (../shared/models, the real parts) whose curved top lies within 0.03 mm on
# at least 80 % of its samples (#19).
# Installs prusa-slicer through scripts/setup.sh if needed, and builds.
set -euo pipefail
cd "$(dirname "$0")/.."
SETUP_ARGS=--with-prusaslicer bash scripts/build.sh >/dev/null
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
models=("$@")
if ((${#models[@]} == 0)); then
  ./build/bench/make_test_solids "$tmp/solids"
  models=("$tmp"/solids/saddle.stl "$tmp"/solids/sine_roof.stl "$tmp"/solids/domed_towers.stl
          "$tmp"/solids/dome_cut_by_box.stl "$tmp"/solids/rib.stl "$tmp"/solids/rib_beside_tower.stl
          "$tmp"/solids/hollow_roof_1.5mm.stl "$tmp"/solids/hollow_roof_0.8mm.stl
          "$tmp"/solids/rib_and_domed_tower.stl "$tmp"/solids/two_reliefs.stl
          "$tmp"/solids/mouse_shell.stl "$tmp"/solids/top_over_pocket.stl
          "$tmp"/solids/tops_one_over_another.stl "$tmp"/solids/filleted_block.stl
          "$tmp"/solids/terrain_tile.stl
          ../shared/models/np_curvislicer_wing.stl
          ../shared/models/np_curvislicer_FoilCutter.stl ../shared/models/np_prusa_sphere.stl
          examples/wave_roof.stl ../shared/models/np_curvislicer_anklebase_small.stl
          ../shared/models/np_curvislicer_car_med.stl ../shared/models/np_curvislicer_airfoil.stl
          ../shared/models/np_voron_sphere_ornament_shellA.stl
          ../shared/models/np_openscad_example010_heightmap.stl ../shared/models/gen_3DBenchy.stl
          ../shared/models/np_slic3r_nonplanar_spikey_top.stl)
fi
common=(--layer-height 0.2 --first-layer-height 0.2 --perimeters 2 --top-solid-layers 5
        --bottom-solid-layers 4 --fill-density 20% --fill-pattern rectilinear --skirts 1
        --nozzle-diameter 0.4 --filament-diameter 1.75 --temperature 210 --bed-temperature 60)
# One row per slicer: deviation p95 / mean / max (mm), thickness min-max (mm), steepest (deg),
# collisions; nonplanar's rows also say how many curved stacks (or shells) it printed: with its
# built-in planar engine, and with PrusaSlicer as the engine (--engine prusaslicer).
# "curved": the share of the curved top's samples (facets 2-30 deg) within 0.03 mm (#19).
figures() {
  local curved
  curved=$(./build/nonplanar check -q --json "$1" --mesh "$2" --min-angle 2 |
    python3 -c 'import json, sys; print("%6.3f" % json.load(sys.stdin)["top_surface_deviation"]["within_share"])')
  ./build/nonplanar check -q --json "$1" --mesh "$2" | python3 -c '
import json, sys
j = json.load(sys.stdin)
d = j["top_surface_deviation"]
print("%7.4f %7.4f %7.4f  %5.3f-%5.3f %6.1f %6d" % (d["p95"], d["mean"], d["max"],
      j["thickness_min"], j["thickness_max"], j["steepest_extrusion"], j["collisions"]), end="")'
  echo " $curved"
}
printf "%-34s %-11s %7s %7s %7s  %-11s %6s %6s %6s  %s\n" model slicer p95 mean max thickness steep coll \
  curved "curved stacks/shells"
real=0 covered=0 covered_ps=0
for m in "${models[@]}"; do
  name=$(basename "$m")
  ./build/nonplanar slice -q "$m" -o "$tmp/np.gcode" "${common[@]}"
  stacks=$(grep -cE '^; patch(es)? .*curved layers' "$tmp/np.gcode" || true)
  ./build/nonplanar slice -q "$m" -o "$tmp/np_ps.gcode" --engine prusaslicer "${common[@]}"
  stacks_ps=$(grep -cE '^; patch(es)? .*curved layers' "$tmp/np_ps.gcode" || true)
  prusa-slicer --export-gcode "${common[@]}" --gcode-flavor marlin2 \
    --bed-shape 0x0,220x0,220x220,0x220 --center 110,110 -o "$tmp/ps.gcode" "$m" >/dev/null 2>&1
  row=$(figures "$tmp/np.gcode" "$m")
  if [[ $m == *shared/models/* ]]; then
    real=$((real + 1))
    awk -v c="${row##* }" 'BEGIN {exit !(c >= 0.8)}' && covered=$((covered + 1))
  fi
  printf "%-34s %-11s %s  %s\n" "$name" nonplanar "$row" "$stacks"
  row_ps=$(figures "$tmp/np_ps.gcode" "$m")
  [[ $m == *shared/models/* ]] && awk -v c="${row_ps##* }" 'BEGIN {exit !(c >= 0.8)}' &&
    covered_ps=$((covered_ps + 1))
  printf "%-34s %-11s %s  %s\n" "" np+engine "$row_ps" "$stacks_ps"
  printf "%-34s %-11s %s\n" "" PrusaSlicer "$(figures "$tmp/ps.gcode" "$m")"
done
echo "real parts (../shared/models) with >= 80 % of the curved top within 0.03 mm: $covered of $real"
echo "the same through PrusaSlicer (--engine prusaslicer): $covered_ps of $real"
