#!/usr/bin/env bash
# Quick start, part 2: build, then run the whole test suite with ctest. Installs prusa-slicer
# too (the external-engine tests slice with it) and chromium (the preview tests open the
# page in it); those tests skip where they are missing.
set -euo pipefail
cd "$(dirname "$0")/.."
SETUP_ARGS="--with-prusaslicer --with-browser ${SETUP_ARGS:-}" bash scripts/build.sh
cd "${BUILD_DIR:-build}"
ctest --output-on-failure -j"$(nproc)" --timeout 600
