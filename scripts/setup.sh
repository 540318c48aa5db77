#!/usr/bin/env bash
# Install every Debian package the build, tests and benchmarks need.
# Idempotent: packages already present are skipped, and apt is not touched at all when
# nothing is missing. Run as root on Debian 12 (uses sudo when not root and available).
#
# Usage: scripts/setup.sh [--with-prusaslicer] [--with-clang] [--with-browser]
#   --with-prusaslicer  also install prusa-slicer (planar reference in benchmarks, the
#                       external engine and its tests); large, so only the test suite,
#                       benchmarks and engine paths ask for it.
#   --with-clang        also install clang-14 and its sanitizer/libFuzzer runtimes
#                       (scripts/sanitize.sh, fuzz/run.sh).
#   --with-browser      also install chromium: the preview tests open the page headless
#                       (software WebGL) and read its screenshot back.
set -euo pipefail

pkgs=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libceres-dev libtbb-dev libpolyclipping-dev lib3mf-dev
  libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  zlib1g-dev zip unzip time
)
for arg in "$@"; do
  case "$arg" in
    --with-prusaslicer) pkgs+=(prusa-slicer) ;;
    --with-clang) pkgs+=(clang-14 libclang-rt-14-dev) ;;
    --with-browser) pkgs+=(chromium) ;;
    *) echo "error: setup: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then SUDO=sudo; else
    echo "error: setup: need root to install: ${missing[*]}" >&2
    exit 1
  fi
fi
echo "setup: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
