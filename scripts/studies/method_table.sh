#!/usr/bin/env bash
# The README's method table from measurements: the conformance suite on CASES drawn hard cases of SEED
# (tests/test_conformance_drawn.cpp, each method at its defaults) gives the cases inside each claim and the
# worst error inside; a sweep gives each method's frame time on `sine` at its defaults. The table between
# README.md's method-table markers is rewritten (scripts/report/method_table.py).
#
# Usage: scripts/studies/method_table.sh SWEEP_DIR [OUT]
#   SWEEP_DIR  a finished sweep with the methods at their defaults on `sine` (scripts/run.sh's quick sweep)
#   OUT        where the drawn cases' CSVs go (default results/studies/method_table)
# Environment: SEED (default 20261205), CASES (default 200; about 20 minutes on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/../.."
sweep=${1:?usage: scripts/studies/method_table.sh SWEEP_DIR [OUT]}
out=${2:-results/studies/method_table}
[ -f "$sweep/results.csv" ] || { echo "method_table.sh: $sweep/results.csv: no such file (a finished sweep)" >&2; exit 2; }
bin=build/release/bin/caustics
drawn=build/release/tests/test_conformance_drawn
for f in "$bin" "$drawn"; do
  [ -x "$f" ] || { echo "method_table.sh: $f: build first (scripts/test.sh or cmake --build --preset release)" >&2; exit 2; }
done
rm -rf "$out"
mkdir -p "$out"
# The CSVs are written before a test's last checks, so a failed test (a claim missed on a drawn case, or the
# mutation check: docs/conformance.md says which methods fail it at 200 cases) still leaves its measurements;
# the table is written from them and the failures are reported with exit status 1.
status=0
CAUSTICS_CONFORMANCE_SEED=${SEED:-20261205} CAUSTICS_CONFORMANCE_CASES=${CASES:-200} \
  CAUSTICS_CONFORMANCE_CSV_DIR="$out" "$drawn" > "$out/drawn.log" || status=1
"$bin" list --json > "$out/methods.json"
/usr/bin/python3 scripts/report/method_table.py --drawn "$out" --sweep "$sweep" --methods "$out/methods.json" \
  --claims scripts/studies/method_claims.json --readme README.md
echo "README.md: method table rewritten from $out and $sweep" >&2
if [ "$status" -ne 0 ]; then
  echo "method_table.sh: failed in the drawn suite (see $out/drawn.log):" >&2
  grep -A1 ': Failure$' "$out/drawn.log" | grep -v -e '^--$' -e ': Failure$' >&2 || true
fi
exit "$status"
