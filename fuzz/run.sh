#!/usr/bin/env bash
# Build the parser fuzzer with clang-14 (libFuzzer, AddressSanitizer, UndefinedBehaviorSanitizer)
# and run it. Usage: fuzz/run.sh [SECONDS=60]. Seeds: ../shared/models and tests/data.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
out=build-fuzz
mkdir -p "$out/corpus"
srcs=(src/io/mesh_buffer.cpp src/io/stl_reader.cpp src/io/obj_reader.cpp src/io/off_reader.cpp
      src/config/print_config.cpp src/config/config_loader.cpp src/check/gcode_reader.cpp
      src/nurbs/surface_io.cpp src/nurbs/nurbs_surface.cpp src/nurbs/bspline_basis.cpp
      src/core/atomic_file.cpp src/core/status.cpp src/gcode/gcode_writer.cpp
      src/toolpaths/make_toolpaths.cpp src/toolpaths/perimeters.cpp src/toolpaths/infill.cpp
      src/toolpaths/ordering.cpp src/slice/polygon_ops.cpp)
clang++-14 -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -Iinclude -Isrc -I/usr/include/eigen3 -I/usr/include/lib3mf \
  fuzz/fuzz_parsers.cpp "${srcs[@]}" -lpolyclipping -ltbb -o "$out/fuzz_parsers"
# Seeds: each shared model under each parser's selector byte (small files only).
for f in ../shared/models/*.{stl,obj,off} tests/data/*.ini; do
  [[ -f $f && $(stat -c %s "$f") -lt 300000 ]] || continue
  for sel in 0 1 2 3; do { printf "\\x0$sel"; cat "$f"; } >"$out/corpus/$(basename "$f").$sel"; done
done
printf '\x04{"layer_height": 0.2, "fill_density": "20%%"}' >"$out/corpus/profile.json"
printf '\x06G90\nM83\nG1 X1 Y2 Z0.2 E0.5 F1200\nG92 E0\n;TYPE:Perimeter\n' >"$out/corpus/g.gcode"
"$out/fuzz_parsers" -max_total_time="$secs" -rss_limit_mb=2048 -max_len=65536 "$out/corpus"
