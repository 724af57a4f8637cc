#!/usr/bin/env bash
# Builds the Release configuration and runs the project's main job: until the sweep runner lands, it
# renders every built-in scene with every registered method (methods that do not support a scene record
# status "skipped" with the reason) and writes everything under results/:
#   results/render/<scene>/<method>/{receiver.exr,camera.exr,beauty.png,metrics.json}
#   results/cache/      the reference cache (reused by later runs)
# Environment: PHOTONS (reference photons, default 4000000), REPEATS (default 10), WARMUP (default 3),
# THREADS (default: all cores), POOL_FRAME (default 60).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset release -G Ninja >/dev/null
cmake --build --preset release -j "$jobs"

bin=build/release/harness/cli/caustics
photons=${PHOTONS:-4000000}
repeats=${REPEATS:-10}
warmup=${WARMUP:-3}
threads=${THREADS:-0}
pool_frame=${POOL_FRAME:-60}
export CAUSTICS_CACHE_DIR="${CAUSTICS_CACHE_DIR:-$PWD/results/cache}"

methods=$("$bin" list --json | python3 -c 'import json,sys; print(" ".join(m["name"] for m in json.load(sys.stdin)["methods"]))')
summary=results/render/summary.txt
mkdir -p results/render
: >"$summary.tmp"
failed=0
for scene_file in scenes/*.json; do
  scene=$(basename "$scene_file" .json)
  frame=0
  [ "$scene" = pool ] && frame=$pool_frame
  for method in $methods; do
    out=results/render/$scene/$method
    echo "== $scene (frame $frame) x $method -> $out" >&2
    if "$bin" render "$scene_file" --method "$method" --frame "$frame" --out "$out" --photons "$photons" \
         --repeats "$repeats" --warmup "$warmup" --threads "$threads" | tee -a "$summary.tmp"; then
      :
    else
      echo "FAILED: $scene x $method (exit $?)" | tee -a "$summary.tmp" >&2
      failed=$((failed + 1))
    fi
  done
done
mv "$summary.tmp" "$summary"
echo
echo "run.sh: wrote results/render/<scene>/<method>/ (receiver.exr, camera.exr, beauty.png, metrics.json)"
echo "run.sh: one line per run in $summary; reference cache in $CAUSTICS_CACHE_DIR"
[ "$failed" -eq 0 ] || { echo "run.sh: $failed run(s) failed" >&2; exit 1; }
