#!/usr/bin/env bash
# Time `nonplanar analyze` against `prusa-slicer --info` on the same 1.3M-triangle STL
# (np_prusa_sphere.stl subdivided 5 times), same machine, same run; print the ratio.
# Usage: bench/compare_prusa_info.sh [RUNS=3]
# Installs prusa-slicer through scripts/setup.sh if needed, and builds.
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
SETUP_ARGS=--with-prusaslicer bash scripts/build.sh >/dev/null
mesh=$(mktemp -d)/dense.stl
tfile=$(dirname "$mesh")/time.txt
trap 'rm -rf "$(dirname "$mesh")"' EXIT
./build/bench/make_dense_mesh "$mesh"

# best of N wall-clock seconds and the peak RSS of that run, via GNU time
best() {
  local best_t=999999 best_m=0 t m
  for _ in $(seq "$runs"); do
    /usr/bin/time -o "$tfile" -f "%e %M" "$@" >/dev/null 2>&1 || true
    read -r t m < <(tail -1 "$tfile")
    if awk -v a="$t" -v b="$best_t" 'BEGIN{exit !(a<b)}'; then best_t=$t best_m=$m; fi
  done
  echo "$best_t $best_m"
}
command -v /usr/bin/time >/dev/null || { echo "error: /usr/bin/time (package time) is needed" >&2; exit 1; }
read -r np_t np_m < <(best ./build/nonplanar analyze -q "$mesh")
read -r ps_t ps_m < <(best prusa-slicer --info "$mesh")
printf "mesh: %s (1310720 triangles)\n" "$mesh"
printf "nonplanar analyze : %6.2f s  peak %7d KB\n" "$np_t" "$np_m"
printf "prusa-slicer --info: %6.2f s  peak %7d KB\n" "$ps_t" "$ps_m"
awk -v a="$np_t" -v b="$ps_t" -v c="$np_m" -v d="$ps_m" \
  'BEGIN{printf "ratio nonplanar/prusa-slicer: time %.2f, memory %.2f\n", a/b, c/d}'
