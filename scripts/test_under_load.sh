#!/usr/bin/env bash
# Runs the whole ctest suite RUNS times (default 3) while LOOPS busy loops (default 2) compete for the
# same cores, to find tests that depend on timing: every test must pass on a loaded machine. Expects the
# release build of scripts/test.sh (build/release). Prints each run's summary line and the tests that
# failed (the log of a failing run is kept and named); exit status non-zero when any run failed.
#
# Usage: scripts/test_under_load.sh [RUNS] [LOOPS] [CTEST ARGS]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
loops=${2:-2}
shift $(( $# > 2 ? 2 : $# ))
pids=()
stop_loops() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; }
trap stop_loops EXIT
for _ in $(seq "$loops"); do
  ( while :; do :; done ) &
  pids+=("$!")
done
export CAUSTICS_CACHE_DIR="${CAUSTICS_CACHE_DIR:-$PWD/build/release/test-cache}"
failed=0
for run in $(seq "$runs"); do
  log=$(mktemp)
  start=$(date +%s)
  if ctest --preset release -j "$(nproc 2>/dev/null || echo 2)" --output-on-failure "$@" >"$log" 2>&1; then status=passed; else status=FAILED; failed=1; fi
  echo "run $run of $runs beside $loops busy loop(s): $status in $(( $(date +%s) - start )) s; load $(cut -d' ' -f1-3 /proc/loadavg)"
  grep -E 'tests passed|tests failed' "$log" || true
  grep -E '^\s+[0-9]+ - .*\((Failed|Timeout|SEGFAULT|Subprocess|Exception)' "$log" || true
  if [[ $status == passed ]]; then rm -f "$log"; else echo "  log kept: $log"; fi
done
exit "$failed"
