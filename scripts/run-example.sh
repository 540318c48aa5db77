#!/usr/bin/env bash
# Quick start, part 1: build, then analyse the bundled example and show its patches.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
mkdir -p out
./build/nonplanar analyze examples/wing.stl --export-patches out/wing-patches.ply
echo "patch colours written to out/wing-patches.ply (open it in any mesh viewer)"
