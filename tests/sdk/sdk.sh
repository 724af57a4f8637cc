#!/usr/bin/env bash
# Helpers for tests that build methods against an installed caustics, as a user outside the repository
# would. Source it for the functions, or run it: `sdk.sh install BUILD PREFIX`, `sdk.sh clean PREFIX`.
#
#   sdk_install BUILD PREFIX             cmake --install BUILD into a fresh PREFIX, checked
#   sdk_build_method PREFIX SOURCE OUT   configure SOURCE (a project calling caustics_add_method) against
#                                        PREFIX with Ninja into OUT, build it and run its tests; the plugin
#                                        libraries end up in OUT/plugins
#   sdk_expect_refusal WHAT TEXT CMD...  CMD exits 2 with one "caustics: error:" line matching *TEXT* (a
#                                        glob pattern)
#
# CAUSTICS_SDK_CXX (default c++) is the compiler of the method's build, CAUSTICS_SDK_LAUNCHER (e.g.
# ccache) its compiler launcher.
set -euo pipefail

sdk_fail() {
    echo "FAIL: $*" >&2
    exit 1
}

sdk_install() {
    local build=$1 prefix=$2
    rm -rf "$prefix"
    cmake --install "$build" --prefix "$prefix" >/dev/null
    local f
    for f in bin/caustics lib/cmake/caustics/caustics-config.cmake share/caustics/scenes/sine.json \
             share/caustics/scripts/report/report.py include/caustics/api/method.hpp; do
        [[ -e $prefix/$f ]] || sdk_fail "the installation lacks $f"
    done
    echo "installed $(du -sh "$prefix" | cut -f1) into $prefix"
}

sdk_build_method() {
    local prefix=$1 source=$2 out=$3
    local launcher=()
    [[ -n ${CAUSTICS_SDK_LAUNCHER:-} ]] && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$CAUSTICS_SDK_LAUNCHER")
    # No CMAKE_BUILD_TYPE: the package's default (Release) is what a user gets.
    cmake -S "$source" -B "$out" -G Ninja -DCMAKE_PREFIX_PATH="$prefix" \
        -DCMAKE_CXX_COMPILER="${CAUSTICS_SDK_CXX:-c++}" "${launcher[@]}" >"$out.configure.log" 2>&1 || { cat "$out.configure.log" >&2; sdk_fail "configure $source"; }
    cmake --build "$out" -j2 || sdk_fail "build $source against $prefix"
    ctest --test-dir "$out" --output-on-failure || sdk_fail "the tests of $source"
}

sdk_expect_refusal() {
    local what=$1 text=$2
    shift 2
    local err code=0
    err=$("$@" 2>&1 >/dev/null) || code=$?
    [[ $code == 2 ]] || sdk_fail "$what: exit $code, expected 2: $err"
    [[ $err == "caustics: error: "* ]] || sdk_fail "$what: not one error line: $err"
    [[ $(printf '%s\n' "$err" | wc -l) == 1 ]] || sdk_fail "$what: more than one line: $err"
    # shellcheck disable=SC2053 # TEXT is a pattern
    [[ $err == *$text* ]] || sdk_fail "$what: the message does not say '$text': $err"
    echo "refused ($what): $err"
}

if [[ ${BASH_SOURCE[0]} == "$0" ]]; then
    case ${1:-} in
    install) sdk_install "$2" "$3" ;;
    clean) rm -rf "$2" ;;
    *) echo "usage: sdk.sh install BUILD PREFIX | clean PREFIX" >&2; exit 2 ;;
    esac
fi
