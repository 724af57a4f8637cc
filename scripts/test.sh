#!/usr/bin/env bash
# Builds and runs the whole test suite with ctest, after fuzzing the scene loader for a minute.
#
#   scripts/test.sh [CTEST ARGS]              Release build, scripts/fuzz.sh 60, then every test
#                                             (CAUSTICS_FUZZ_SECONDS=0 skips the fuzz run)
#   scripts/test.sh --sanitize [CTEST ARGS]   the same suite built with AddressSanitizer and
#                                             UndefinedBehaviorSanitizer (preset asan; any report fails)
set -euo pipefail
cd "$(dirname "$0")/.."
preset=release
if [ "${1:-}" = "--sanitize" ]; then
  preset=asan
  shift
fi
scripts/setup.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset "$preset" -G Ninja >/dev/null
cmake --build --preset "$preset" -j "$jobs"
# The fuzz run first, so that ctest's summary is the last thing printed.
if [ "$preset" = release ] && [ "${CAUSTICS_FUZZ_SECONDS:-60}" != 0 ] && [ $# -eq 0 ]; then
  scripts/fuzz.sh "${CAUSTICS_FUZZ_SECONDS:-60}"
fi
export CAUSTICS_CACHE_DIR="${CAUSTICS_CACHE_DIR:-$PWD/build/$preset/test-cache}"
ctest --preset "$preset" -j "$jobs" "$@"
