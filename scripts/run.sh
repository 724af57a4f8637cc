#!/usr/bin/env bash
# The project's main job: builds the Release configuration, runs the quick sweep (every method on the
# sine, pool and sphere scenes with small axes; methods that do not support a scene are recorded as
# skipped with their reason) and writes its report. The last line printed is the path of report.md.
#
#   results/sweeps/quick-<date>/  results.csv, results.jsonl, manifest.json, references/, runs/<id>/,
#                                 report.md, figures/*.png|pdf, tables/*.tex|md
#   results/cache/                the reference cache (reused by later runs)
#
# Usage: scripts/run.sh [SPEC] [extra `caustics sweep` options, e.g. --axis caustic_triangles.grid=[64]]
# Environment: THREADS (worker threads per run, default all cores), OUT (output folder).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset release -G Ninja >/dev/null
cmake --build --preset release -j "$jobs" --target caustics

spec=${1:-scripts/sweeps/quick.json}
[ $# -gt 0 ] && shift
out=${OUT:-results/sweeps/$(basename "$spec" .json)-$(date +%Y%m%d-%H%M%S)}
export CAUSTICS_CACHE_DIR="${CAUSTICS_CACHE_DIR:-$PWD/results/cache}"
bin=build/release/bin/caustics

"$bin" sweep "$spec" --out "$out" --threads "${THREADS:-0}" "$@" >&2
"$bin" report "$out"
