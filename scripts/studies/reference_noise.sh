#!/usr/bin/env bash
# The reference's noise against photons for both samplers (issue 11's benchmark): for each scene and
# sampler, `caustics reference` at doubling photon counts into a private cache (nothing reused), then a
# least-squares fit of log(noise_nrmse) against log(photons). Prints one table row per run and the
# fitted slopes; writes OUT/noise.csv.
#
# Usage: scripts/studies/reference_noise.sh [OUT] [SCENES...]   (default: sine pool sphere)
# Environment: PHOTONS (space-separated counts, default "1000000 4000000 16000000 64000000"), THREADS.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-results/studies/reference_noise}
shift || true
scenes=("$@")
[ ${#scenes[@]} -eq 0 ] && scenes=(sine pool sphere)
photons=${PHOTONS:-"1000000 4000000 16000000 64000000"}
bin=build/release/bin/caustics
[ -x "$bin" ] || { echo "reference_noise.sh: build first (scripts/test.sh or cmake --build --preset release)" >&2; exit 1; }
mkdir -p "$out"
cache=$(mktemp -d)
trap 'rm -rf "$cache"' EXIT
echo "scene,frame,sampler,photons,noise_nrmse,seconds" > "$out/noise.csv.tmp"
for scene in "${scenes[@]}"; do
  frame=0
  [ "$scene" = pool ] && frame=30
  for sampler in sobol independent; do
    for n in $photons; do
      dir="$out/$scene-$sampler-$n"
      "$bin" reference "$scene" --frame "$frame" --photons "$n" --sampler "$sampler" --cache "$cache" \
        --threads "${THREADS:-0}" --out "$dir" > /dev/null
      /usr/bin/python3 - "$dir/reference.json" "$scene" "$frame" "$sampler" >> "$out/noise.csv.tmp" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{r['photons']},{r['noise_nrmse']},{r['seconds']}")
PY
      rm -rf "$cache"/*
    done
  done
done
mv "$out/noise.csv.tmp" "$out/noise.csv"
/usr/bin/python3 - "$out/noise.csv" <<'PY'
import sys
import numpy as np
import pandas as pd
d = pd.read_csv(sys.argv[1])
print(d.to_string(index=False))
print()
print("scene   sampler      slope  (noise ~ photons^slope)  photons for noise 0.01 (extrapolated)")
for (scene, sampler), g in d.groupby(["scene", "sampler"]):
    slope, icpt = np.polyfit(np.log(g.photons), np.log(g.noise_nrmse), 1)
    need = np.exp((np.log(0.01) - icpt) / slope)
    rate = (g.photons / g.seconds).median()
    print(f"{scene:7s} {sampler:12s} {slope:6.3f}  {need:12.3g} photons, ~{need / rate:6.0f} s at {rate:.3g} photons/s")
PY
