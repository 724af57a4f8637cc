#!/usr/bin/env bash
# The scaffold round trip: scripts/new_method.sh stamps a method into a fresh standalone project
# (--dir), which is built against the installed PREFIX (sdk.sh) with its own stamped tests run; then the
# installed program, from a working folder outside the source tree, lists the method from
# CAUSTICS_PLUGIN_PATH and renders it on the sine scene against the analytic truth. The stamped skeleton
# draws the no-caustic baseline, so its receiver error must be the baseline's error.
#
#   scaffold_round_trip.sh SOURCE_DIR      (the installation: $CAUSTICS_SDK_PREFIX, tests/sdk/CMakeLists.txt)
set -euo pipefail
prefix=${CAUSTICS_SDK_PREFIX:?the installed prefix}
source_dir=$1
source "$source_dir/tests/sdk/sdk.sh"

work=$(mktemp -d "${TMPDIR:-/tmp}/caustics_scaffold.XXXXXX")
trap 'rm -rf "$work"' EXIT
caustics=$prefix/bin/caustics
name=scaffold_round_trip

# The name check asks the installed program which names are taken.
CAUSTICS_BIN=$caustics "$source_dir/scripts/new_method.sh" "$name" --dir "$work/project" >"$work/stamp.log" 2>&1 ||
    { cat "$work/stamp.log" >&2; sdk_fail "new_method.sh $name --dir"; }
[[ $(cat "$work/project/$name/CMakeLists.txt") == "caustics_add_method($name)" ]] ||
    sdk_fail "the stamped CMakeLists.txt is not the one line"
sdk_build_method "$prefix" "$work/project" "$work/build"
plugins=$work/build/plugins
[[ -f $plugins/$name.so ]] || sdk_fail "no plugin library $name.so in $plugins"

mkdir "$work/run"
cd "$work/run"
list=$(CAUSTICS_PLUGIN_PATH=$plugins "$caustics" list) || sdk_fail "caustics list with the stamped plugin"
[[ $list == *"$name  [radiometric]"* ]] || sdk_fail "caustics list does not show $name: $list"
CAUSTICS_PLUGIN_PATH=$plugins "$caustics" render sine --method "$name" --out out --warmup 1 --repeats 3 \
    --max-time 1 --photons 20000 --cache cache >render.log 2>&1 || { cat render.log >&2; sdk_fail "caustics render"; }
for f in receiver.exr camera.exr metrics.json; do
    [[ -s out/$f ]] || sdk_fail "render wrote no $f"
done
/usr/bin/python3 - out/metrics.json "$name" <<'PY' || sdk_fail "metrics.json"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["method"] == sys.argv[2] and m["status"] == "ok", (m["method"], m["status"])
assert m["truth"]["kind"].startswith("analytic"), m["truth"]
r, b = m["error"]["receiver"]["nrmse"], m["baseline"]["error"]
# The skeleton's grid map of the baseline, averaged over sub-bin lookups: within 1 % of its error.
assert abs(r - b) <= 0.01 * b, (r, b)
PY
echo "stamped, built, tested, listed and rendered $name from $plugins"
