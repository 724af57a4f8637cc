#!/usr/bin/env bash
# Fuzzes the scene loader and frame set-up (tests/fuzz/fuzz_scene_loader.cpp) with libFuzzer under
# AddressSanitizer and UndefinedBehaviorSanitizer, starting from the shipped scenes, for SECONDS
# (default 60). The regression inputs in tests/fuzz/regressions/ (inputs that once found a bug) are run
# first. Exit status non-zero on any finding; the input that found it is left in build/fuzz/findings/.
#
# Usage: scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
scripts/setup.sh
cmake --preset fuzz -G Ninja >/dev/null
cmake --build --preset fuzz -j "$(nproc 2>/dev/null || echo 2)"
bin=build/fuzz/tests/fuzz/fuzz_scene_loader
corpus=$(mktemp -d)
trap 'rm -rf "$corpus"' EXIT
cp scenes/*.json "$corpus"/
mkdir -p build/fuzz/findings
export ASAN_OPTIONS=halt_on_error=1:detect_leaks=0
export UBSAN_OPTIONS=print_stacktrace=1   # -fno-sanitize-recover: undefined behaviour halts
if compgen -G "tests/fuzz/regressions/*" >/dev/null; then
  "$bin" -rss_limit_mb=4096 -timeout=30 tests/fuzz/regressions/*
fi
"$bin" -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=30 -dict=tests/fuzz/scene.dict \
  -artifact_prefix=build/fuzz/findings/ -print_final_stats=1 "$corpus" 2>&1 | tail -n 25
