#!/usr/bin/env bash
# Quick start, part 1: build, then slice the bundled example with non-planar top layers,
# write its 3D preview page and a cross-section of its layers, and print the quality figures
# (beside PrusaSlicer's planar slicing of the same model when prusa-slicer is installed).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
model=examples/wave_roof.stl
mkdir -p out
./build/nonplanar slice "$model" -o out/wave_roof.gcode --preview
./build/nonplanar layers -q "$model" --section out/wave_roof_section.svg --at y=110 >/dev/null
echo "cross-section of the layers: out/wave_roof_section.svg"
echo
./build/nonplanar check -q out/wave_roof.gcode --mesh "$model"
if command -v prusa-slicer >/dev/null; then
  prusa-slicer --export-gcode --layer-height 0.2 --first-layer-height 0.2 --perimeters 2 \
    --top-solid-layers 5 --bottom-solid-layers 4 --fill-density 20% --fill-pattern rectilinear \
    --nozzle-diameter 0.4 --filament-diameter 1.75 --bed-shape 0x0,220x0,220x220,0x220 \
    --center 110,110 -o out/wave_roof_prusaslicer.gcode "$model" >/dev/null 2>&1
  echo
  echo "PrusaSlicer (planar), same model and settings:"
  ./build/nonplanar check -q out/wave_roof_prusaslicer.gcode --mesh "$model"
else
  echo
  echo "(install prusa-slicer to see its planar figures beside these: scripts/setup.sh --with-prusaslicer)"
fi
