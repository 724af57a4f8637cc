#!/usr/bin/env bash
# Builds (Release) and runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset release -G Ninja >/dev/null
cmake --build --preset release -j "$jobs"
export CAUSTICS_CACHE_DIR="${CAUSTICS_CACHE_DIR:-$PWD/build/release/test-cache}"
ctest --preset release -j "$jobs" "$@"
