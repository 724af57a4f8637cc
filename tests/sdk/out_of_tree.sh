#!/usr/bin/env bash
# The out-of-tree round trip: examples/out_of_tree_method built against the installed PREFIX (sdk.sh),
# its test run, and the installed program loading it from CAUSTICS_PLUGIN_PATH in a working folder
# outside the source tree: `caustics list` shows it, `caustics render` runs it. Then the libraries the
# program must refuse at start-up, each with exit 2 and one message: one that fails to load, one that is
# not a plugin, one built against another version, a second library registering the same name, a plugin
# taking a built-in method's name, and a plugin folder that does not exist.
#
#   out_of_tree.sh SOURCE_DIR      (the installation: $CAUSTICS_SDK_PREFIX, tests/sdk/CMakeLists.txt)
set -euo pipefail
prefix=${CAUSTICS_SDK_PREFIX:?the installed prefix}
source_dir=$1
source "$source_dir/tests/sdk/sdk.sh"

work=$(mktemp -d "${TMPDIR:-/tmp}/caustics_out_of_tree.XXXXXX")
trap 'rm -rf "$work"' EXIT
caustics=$prefix/bin/caustics

sdk_build_method "$prefix" "$source_dir/examples/out_of_tree_method" "$work/build"
plugins=$work/build/plugins
[[ -f $plugins/flat_field.so ]] || sdk_fail "no plugin library in $plugins"

mkdir "$work/run"
cd "$work/run"
list=$(CAUSTICS_PLUGIN_PATH=$plugins "$caustics" list) || sdk_fail "caustics list with the plugin"
[[ $list == *"flat_field  [radiometric]"* ]] || sdk_fail "caustics list does not show flat_field: $list"
[[ $list == *"registered by $plugins/flat_field.so (flat_field.cpp:"* ]] || sdk_fail "flat_field's origin is not its library"
[[ $list == *"Scenes ($prefix/share/caustics/scenes)"* ]] || sdk_fail "the scenes are not the installation's"

CAUSTICS_PLUGIN_PATH=$plugins "$caustics" render sine --method flat_field --out out --warmup 1 --repeats 3 \
    --max-time 1 --photons 20000 --cache cache >render.log 2>&1 || { cat render.log >&2; sdk_fail "caustics render"; }
for f in receiver.exr camera.exr beauty.png metrics.json; do
    [[ -s out/$f ]] || sdk_fail "render wrote no $f"
done
# The flat field is the no-caustic baseline itself: its receiver error against the analytic truth is the
# baseline's.
/usr/bin/python3 - out/metrics.json <<'PY' || sdk_fail "metrics.json"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["method"] == "flat_field" and m["status"] == "ok", (m["method"], m["status"])
r = m["error"]["receiver"]
assert m["truth"]["kind"].startswith("analytic"), m["truth"]
assert abs(r["nrmse"] - m["baseline"]["error"]) < 1e-9 * m["baseline"]["error"], (r["nrmse"], m["baseline"])
# Configured with no build type, the plugin was built optimised and says so beside the program's.
assert m["method_build_type"] == "Release", m["method_build_type"]
assert m["build_type"], m["build_type"]
PY
echo "listed and rendered flat_field from $plugins"

# Libraries the program refuses.
version=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["version"])' \
    "$prefix/share/caustics/build.json")
builtin=$("$caustics" list --json | /usr/bin/python3 -c 'import json, sys; print(json.load(sys.stdin)["methods"][0]["name"])')
compile_plugin() {   # OUT NAME VERSION: a plugin of one method NAME, built by hand as caustics_add_method() would
    ${CAUSTICS_SDK_LAUNCHER:-} "${CAUSTICS_SDK_CXX:-c++}" -std=c++20 -shared -fPIC -fvisibility=hidden -DCAUSTICS_PLUGIN -DGLM_FORCE_XYZW_ONLY \
        -DCAUSTICS_SDK_VERSION="\"$3\"" -DMETHOD_NAME="\"$2\"" -I"$prefix/include" "$work/method.cpp" \
        "$prefix/lib/cmake/caustics/caustics_plugin_entry.cpp" -o "$1"
}
mkdir -p "$work/broken" "$work/not_plugin" "$work/old" "$work/twin" "$work/clash"
echo "not a library" >"$work/broken/broken.so"
echo 'extern "C" int some_function() { return 0; }' >"$work/not_plugin.cpp"
"${CAUSTICS_SDK_CXX:-c++}" -shared -fPIC "$work/not_plugin.cpp" -o "$work/not_plugin/libsomething.so"
cat >"$work/method.cpp" <<CPP
#include <memory>
#include <caustics/api/registry.hpp>
caustics::MethodInfo info() {
    caustics::MethodInfo m;
    m.name = METHOD_NAME;
    m.doc = "a second method of a taken name";
    m.params = {{"grid", caustics::ParamType::Int, "1", 1, 1, {}, "-"},
                {"iterations", caustics::ParamType::Int, "1", 1, 1, {}, "-"}};
    m.create = [](const caustics::ParamSet&) -> std::unique_ptr<caustics::Method> { return nullptr; };
    return m;
}
CAUSTICS_REGISTER_METHOD(info);
CPP
compile_plugin "$work/old/old.so" old 0.0.0
compile_plugin "$work/clash/clash.so" "$builtin" "$version"
cp "$plugins/flat_field.so" "$work/twin/flat_field.so"

sdk_expect_refusal "fails to load" "$work/broken/broken.so: cannot load the library" \
    env CAUSTICS_PLUGIN_PATH="$work/broken" "$caustics" list
sdk_expect_refusal "not a plugin" "$work/not_plugin/libsomething.so: not a caustics plugin" \
    env CAUSTICS_PLUGIN_PATH="$work/not_plugin" "$caustics" list
sdk_expect_refusal "another version" "built against caustics 0.0.0, this program is caustics $version" \
    env CAUSTICS_PLUGIN_PATH="$work/old" "$caustics" list
sdk_expect_refusal "same name twice" \
    "$work/twin/flat_field.so (flat_field.cpp:*): 'flat_field': a method of this name is already registered by $plugins/flat_field.so (" \
    env CAUSTICS_PLUGIN_PATH="$plugins:$work/twin" "$caustics" render sine --method flat_field
sdk_expect_refusal "built-in name" "$work/clash/clash.so (method.cpp:*): '$builtin': a method of this name is already registered by methods/$builtin/" \
    env CAUSTICS_PLUGIN_PATH="$work/clash" "$caustics" list
sdk_expect_refusal "no such folder" "CAUSTICS_PLUGIN_PATH: '$work/none' is not a folder" \
    env CAUSTICS_PLUGIN_PATH="$work/none" "$caustics" list
echo "out-of-tree round trip passed"
