#!/usr/bin/env bash
# Stamps out a new method from scripts/method_template/: a documented skeleton that compiles, renders (it
# draws the no-caustic baseline until its own work replaces it), and passes its own tests.
#
#   scripts/new_method.sh NAME             methods/NAME/ in this repository; methods/CMakeLists.txt picks the
#                                          folder up at the next build, so nothing else is edited
#   scripts/new_method.sh NAME --dir DIR   DIR/NAME/ and DIR/CMakeLists.txt: a standalone project that builds
#                                          the method against an installed harness (find_package(caustics));
#                                          an existing DIR/CMakeLists.txt gets the add_subdirectory(NAME) line
#
# Files: NAME/CMakeLists.txt (the one line caustics_add_method(NAME)), NAME/NAME.cpp, NAME/README.md,
# NAME/tests/test_NAME.cpp. NAME is a lower-case C++ identifier that no method, test program or namespace
# of the project uses yet. A bad name or usage is exit 2 with one message, and nothing is written. The
# method folder is assembled under a temporary name and renamed into place; nothing is overwritten.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
template="$root/scripts/method_template"
usage="usage: scripts/new_method.sh NAME [--dir DIR]"

fail() {
  echo "new_method.sh: error: $1" >&2
  exit 2
}

name=""
dir=""
while [ $# -gt 0 ]; do
  case "$1" in
    -h | --help) echo "$usage"; exit 0 ;;
    --dir)
      [ $# -ge 2 ] && [ -n "$2" ] || fail "--dir: needs a folder; $usage"
      [ -z "$dir" ] || fail "--dir: given twice; $usage"
      dir="$2"
      shift 2
      ;;
    --dir=*)
      [ -z "$dir" ] || fail "--dir: given twice; $usage"
      dir="${1#--dir=}"
      [ -n "$dir" ] || fail "--dir: needs a folder; $usage"
      shift
      ;;
    -*) fail "$1: unknown option; valid: --dir DIR, --help" ;;
    *)
      [ -z "$name" ] || fail "$1: a second NAME (already '$name'); $usage"
      name="$1"
      shift
      ;;
  esac
done
[ -n "$name" ] || fail "NAME is missing; $usage"

# --- the name ------------------------------------------------------------------------------------------
valid="a lower-case identifier of at most 48 characters ([a-z][a-z0-9_]*, no '__'), e.g. my_method"
# Shown escaped (printf %q) while it is not yet known to be an identifier: a newline or a control character in
# it would otherwise split the one-line message.
[[ "$name" =~ ^[a-z][a-z0-9_]*$ ]] || fail "NAME $(printf '%q' "$name"): not a lower-case identifier; valid: $valid"
[ ${#name} -le 48 ] || fail "NAME '$name': longer than 48 characters; valid: $valid"
[[ "$name" != *__* ]] || fail "NAME '$name': '__' is reserved in C++ identifiers; valid: $valid"
# NAME becomes a namespace inside caustics: no keyword, no namespace the code uses, no C library macro.
reserved=" alignas alignof and and_eq asm auto bitand bitor bool break case catch char char8_t char16_t
  char32_t class compl concept const consteval constexpr constinit const_cast continue co_await co_return
  co_yield decltype default delete do double dynamic_cast else enum explicit export extern false final
  float for friend goto if import inline int long module mutable namespace new noexcept not not_eq nullptr
  operator or or_eq override private protected public register reinterpret_cast requires return short
  signed sizeof static static_assert static_cast struct switch template this thread_local throw true try
  typedef typeid typename union unsigned using virtual void volatile wchar_t while xor xor_eq
  std glm tbb nlohmann embree caustics cli detail test_support errno stdin stdout stderr assert unix linux "
[[ "$reserved" != *" $name "* ]] ||
  fail "NAME '$name': a C++ keyword or a name the code already uses (std, glm, tbb, caustics, ...); valid: $valid"

# The places a method of this name could already be: this repository's methods and tests, the target
# folder, and the methods a built `caustics` program registers.
project_dirs=("$root/methods")
[ -n "$dir" ] && [ -d "$dir" ] && project_dirs+=("$dir")
for d in "${project_dirs[@]}"; do
  [ ! -e "$d/$name" ] || fail "NAME '$name': $d/$name already exists; choose another name"
  if grep -rqsE "caustics_add_method\($name[ )]" --include=CMakeLists.txt "$d"; then
    fail "NAME '$name': a method of that name is already added in $d; choose another name"
  fi
done
for f in "$root"/tests/test_"$name".cpp "$root"/methods/*/tests/test_"$name".cpp; do
  [ ! -e "$f" ] || fail "NAME '$name': its test program test_$name would clash with $f; choose another name"
done
if grep -rqsE "namespace (caustics::)?$name( |\{|$)" --include='*.hpp' --include='*.cpp' "$root/harness" "$root/methods"; then
  fail "NAME '$name': the namespace caustics::$name is already used in $root; choose another name"
fi
program="${CAUSTICS_BIN:-$root/build/release/bin/caustics}"
[ -x "$program" ] || program=$(command -v caustics || true)
if [ -n "$program" ] && command -v python3 >/dev/null; then
  registered=$("$program" list --json 2>/dev/null |
    python3 -c 'import json, sys; print(" ".join(m["name"] for m in json.load(sys.stdin)["methods"]))' 2>/dev/null || true)
  [[ " $registered " != *" $name "* ]] ||
    fail "NAME '$name': $program already registers a method of that name (rebuild it if its folder was removed); choose another name"
fi

# --- where ---------------------------------------------------------------------------------------------
if [ -n "$dir" ]; then
  [ ! -e "$dir" ] || [ -d "$dir" ] || fail "--dir $dir: exists and is not a folder; valid: a folder, or a path to create"
  mkdir -p "$dir" 2>/dev/null || fail "--dir $dir: cannot be created; valid: a folder that can be written"
  [ -w "$dir" ] || fail "--dir $dir: cannot be written; valid: a folder that can be written"
  parent=$(cd "$dir" && pwd)
else
  parent="$root/methods"
fi
target="$parent/$name"
suite=$(echo "$name" | sed -E 's/(^|_)([a-z])/\U\2/g')   # my_method: MyMethod, its tests' suite name
class="${suite}Method"

# --- the files -----------------------------------------------------------------------------------------
tmp=$(mktemp -d "$parent/.$name.XXXXXX")
trap 'rm -rf "$tmp" "$tmp.cmake"' EXIT
stamp() {   # stamp TEMPLATE DESTINATION: the template with the names filled in
  sed -e "s/@NAME@/$name/g" -e "s/@CLASS@/$class/g" -e "s/@SUITE@/$suite/g" "$template/$1" >"$tmp/$2"
}
mkdir "$tmp/tests"
echo "caustics_add_method($name)" >"$tmp/CMakeLists.txt"
stamp method.cpp.in "$name.cpp"
stamp README.md.in README.md
stamp test_method.cpp.in "tests/test_$name.cpp"
chmod -R u=rwX,go=rX "$tmp"
mv -n -T "$tmp" "$target"
[ ! -e "$tmp" ] || fail "NAME '$name': $target appeared meanwhile; nothing written"

if [ -n "$dir" ]; then
  project="$parent/CMakeLists.txt"
  line="add_subdirectory($name)"
  if [ ! -e "$project" ]; then
    cat >"$tmp.cmake" <<EOF
# Methods built against an installed caustics harness: every folder here holds one method (its one
# line: caustics_add_method(NAME)). Configure with CMAKE_PREFIX_PATH pointing at the harness's prefix.
cmake_minimum_required(VERSION 3.25)
project(${name}_methods LANGUAGES CXX)
find_package(caustics REQUIRED)
enable_testing()
$line
EOF
    mv -n "$tmp.cmake" "$project"
  elif ! grep -qxF "$line" "$project"; then
    # Registered by appending its line; the rest of the file is copied unchanged and renamed into place.
    cat "$project" >"$tmp.cmake"
    [ -z "$(tail -c 1 "$project")" ] || echo >>"$tmp.cmake"
    echo "$line" >>"$tmp.cmake"
    mv "$tmp.cmake" "$project"
  fi
  rm -f "$tmp.cmake"
fi

echo "new method '$name' in $target:"
(cd "$target" && find . -type f | sed 's|^\./|  |' | sort)
if [ -n "$dir" ]; then
  echo "build it against an installed harness:"
  echo "  cmake -S $parent -B $parent/build -DCMAKE_PREFIX_PATH=<prefix> && cmake --build $parent/build && ctest --test-dir $parent/build"
else
  echo "next: cmake --build build/release, then"
  echo "  build/release/bin/caustics render sine --method $name"
  echo "  ctest --test-dir build/release -R '^$suite\\.|/${name}__'"
fi
