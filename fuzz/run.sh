#!/usr/bin/env bash
# Run the libFuzzer targets (one per parser; AddressSanitizer + UndefinedBehaviorSanitizer).
# Usage: fuzz/run.sh [SECONDS=60] [TARGET...]
#   TARGET: stl obj off 3mf ini json surfaces gcode foreign toolhead settings macros plan (default: all
#   of them, two at a time; foreign is the mapping of another slicer's G-code,
#   map_foreign_gcode; toolhead is a head shape file, docs/toolhead.md; settings prints a box
#   with any profile that validates and checks the G-code stays on the bed and in range; plan is
#   the print plan a prepared 3MF carries, docs/plan-format.md).
# Builds the missing targets in build-san/ with scripts/sanitize.sh --build-only.
# Seeds come from ../shared/models, tests/data and toolheads/; corpora grow in build-san/corpus/TARGET,
# so longer runs pick up where the last one stopped. Findings are written to
# build-san/findings/ and the script fails when any target crashes, leaks or reports UB.
# To fuzz longer, e.g. an hour per target: fuzz/run.sh 3600
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
shift || true
targets=("$@")
((${#targets[@]})) || targets=(stl obj off 3mf ini json surfaces gcode foreign toolhead settings macros plan)
out=${BUILD_DIR:-build-san}
missing=0
for t in "${targets[@]}"; do [[ -x "$out/fuzz/fuzz_$t" ]] || missing=1; done
if ((missing)); then
  BUILD_DIR=$out bash scripts/sanitize.sh --build-only "${targets[@]/#/fuzz_}"
fi

models=../shared/models
seed() {  # seed TARGET FILE...: copy small files into the target's corpus
  local t=$1
  shift
  mkdir -p "$out/corpus/$t"
  for f in "$@"; do
    [[ -f $f && $(stat -c %s "$f") -lt 300000 ]] && cp "$f" "$out/corpus/$t/" || true
  done
}
seed stl "$models"/*.stl
seed obj "$models"/*.obj
seed off "$models"/*.off
seed ini tests/data/*.ini
seed settings tests/data/*.ini
seed toolhead toolheads/*.json
seed plan tests/data/plan_small.json tests/data/plan_small_b64.json tests/data/plan_shell_small.json
seed 3mf tests/data/*.3mf
mkdir -p "$out/corpus/macros"
printf '%s' 'M862.3 P "[printer_model]"\n{if max_layer_z < 200}G1 Z{z_offset+min(max_layer_z+30, 200)}{else}G1 Z{max_layer_z+1}{endif}\nM104 S[temperature[0]] ; {digits(1.5,2,1)} {printer_notes=~/.*MK3.*/ ? 1 : 0}\n{elsif}' \
  >"$out/corpus/macros/mk3s.gcode"
mkdir -p "$out/corpus/json" "$out/corpus/surfaces" "$out/corpus/gcode" "$out/corpus/3mf" \
  "$out/corpus/foreign" "$out/corpus/settings"
printf 'skirts = 3\nskirt_distance = 30\nbed_shape = 0x0,80x0,80x80,0x80\ntravel_speed = 900\nmax_fan_speed = 100\nextrusion_multiplier = 4.9\nfirst_layer_extrusion_width = 200%%\nlayer_height = 0.05\n' \
  >"$out/corpus/settings/seed.ini"
printf '{"layer_height": 0.2, "fill_density": "20%%", "bed_shape": "0x0,220x0,220x220,0x220"}' \
  >"$out/corpus/json/profile.json"
printf '%s' '{"format":"nonplanar-surfaces","version":1,"surfaces":[{"patch":0,"degree_u":2,'\
'"degree_v":2,"knots_u":[0,0,0,1,1,1],"knots_v":[0,0,0,1,1,1],"control_points":'\
'[[[0,0,0,1],[0,1,0,1],[0,2,0,1]],[[1,0,0,1],[1,1,1,1],[1,2,0,1]],[[2,0,0,1],[2,1,0,1],'\
'[2,2,0,1]]]}]}' >"$out/corpus/surfaces/one.json"
printf 'G90\nM83\nG92 E0\n;LAYER_CHANGE\n;Z:0.2\n;TYPE:Perimeter\nG1 X1 Y2 Z0.2 E0.5 F1200\nG1 E-0.8 F2100\nG0 X5 Y5\n' \
  >"$out/corpus/gcode/moves.gcode"
printf 'M82\nG28\n;LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 Z.2 F7800\nG1 X10 Y10 F7800\n;TYPE:Perimeter\n;WIDTH:0.45\nG1 X30 Y10 E1.2 F1800\n;WIPE_START\nG1 X25 Y10 E-0.4\n;WIPE_END\nG1 E-0.8 F2400\nG92 E0\n;LAYER_CHANGE\n;Z:0.4\n;HEIGHT:0.2\nG1 Z.4\nG1 X40 Y40 F7800\nG1 E0.8\nG1 X45 Y40 E0.3\nM107\n;TYPE:Custom\nG28 X0\n' \
  >"$out/corpus/foreign/two_layers.gcode"
printf 'M83\n;LAYER_CHANGE\n;Z:0.2\n;HEIGHT:0.2\nG1 X10 Y10 Z0.2 F7800\nG1 X20 Y10 E0.5\nG91\nG1 E-0.8\nG1 Z0.4 X2\nG90\nM82\nG92 E0\nG1 X30 Y12 E0.7\nM83\nG1 X32 Y12 E0.1\n; filament used [mm] = 1.0\n' \
  >"$out/corpus/foreign/e_modes.gcode"
# A minimal 3MF package (one tetrahedron), zipped here so no binary lives in the repository.
tmf=$(mktemp -d)
mkdir -p "$tmf/_rels" "$tmf/3D"
printf '<?xml version="1.0" encoding="UTF-8"?>\n<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>' >"$tmf/[Content_Types].xml"
printf '<?xml version="1.0" encoding="UTF-8"?>\n<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>' >"$tmf/_rels/.rels"
printf '<?xml version="1.0" encoding="UTF-8"?>\n<model unit="millimeter" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources><object id="1" type="model"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="10" y="0" z="0"/><vertex x="0" y="10" z="0"/><vertex x="0" y="0" z="10"/></vertices><triangles><triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3"/><triangle v1="1" v2="2" v3="3"/><triangle v1="0" v2="3" v3="2"/></triangles></mesh></object></resources><build><item objectid="1" transform="1 0 0 0 1 0 0 0 1 5 5 0"/></build></model>' >"$tmf/3D/3dmodel.model"
(cd "$tmf" && zip -q -X -r "$OLDPWD/$out/corpus/3mf/tetra.3mf" '[Content_Types].xml' _rels 3D)
# The same with a relationship to a thumbnail it lacks (PrusaSlicer's --export-3mf): the repair.
printf '<?xml version="1.0" encoding="UTF-8"?>\n<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/><Relationship Target="/Metadata/thumbnail.png" Id="rel1" Type="http://schemas.openxmlformats.org/package/2006/relationships/metadata/thumbnail"/></Relationships>' >"$tmf/_rels/.rels"
(cd "$tmf" && zip -q -X -r "$OLDPWD/$out/corpus/3mf/tetra_thumb.3mf" '[Content_Types].xml' _rels 3D)
rm -rf "$tmf"

mkdir -p "$out/findings"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/scripts/lsan.supp:print_suppressions=0}
run_one() {  # run_one TARGET: fuzz for $secs seconds; prints the executions
  local t=$1 log="$out/findings/$1.log"
  if "$out/fuzz/fuzz_$t" -max_total_time="$secs" -rss_limit_mb=2048 -max_len=65536 -timeout=10 \
    -artifact_prefix="$out/findings/$t-" -print_final_stats=1 "$out/corpus/$t" >"$log" 2>&1; then
    echo "fuzz_$t: $(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$') executions in ${secs} s, no findings"
  else
    echo "fuzz_$t: FAILED, see $log:"
    grep -m5 -E 'ERROR|SUMMARY|runtime error' "$log" || tail -5 "$log"
    return 1
  fi
}
export -f run_one
export out secs
printf '%s\n' "${targets[@]}" | xargs -P 2 -I{} bash -c 'run_one {}'
