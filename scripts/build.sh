#!/usr/bin/env bash
# Install what is missing (scripts/setup.sh), configure and build into build/.
# Usage: scripts/build.sh [extra cmake -D options]
# Environment: BUILD_DIR (default build), BUILD_TYPE (default Release); CI=true turns
# warnings into errors.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh ${SETUP_ARGS:-}
build_dir=${BUILD_DIR:-build}
werror=OFF
[[ "${CI:-}" == "true" ]] && werror=ON
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if [[ -f "$build_dir/CMakeCache.txt" ]]; then generator=(); fi  # keep the existing generator
cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" \
  -DNONPLANAR_WERROR="$werror" "$@" >/dev/null
cmake --build "$build_dir" -j"$(nproc)"
