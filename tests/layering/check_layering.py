#!/usr/bin/env python3
"""Checks the dependency direction of docs/architecture.md on the sources and on the build.

  check_layering.py SOURCE_DIR LINKS_FILE   exit 1 listing every violation, 0 if there is none
  check_layering.py --self-test             plants one violation of each kind in a temporary tree and
                                            checks that every one is reported

Rules:
  - a file in harness/<layer>/ includes <caustics/X/...> only for X in the layers it may use;
  - harness/blocks/ is usable by methods only: no framework layer includes it;
  - a method includes only util, scene, frame, api and blocks, and never another method's folder;
  - no file under harness/ names a method (a method's name is its folder under methods/);
  - no method or layer target links a layer it may not use (LINKS_FILE, written by CMake at configure
    time: "target: linked targets", see cmake/CausticsLayering.cmake).
"""
import os
import re
import sys
import tempfile

# What each part may include / link, itself included.
BASE = ["util"]
ALLOWED = {
    "util": BASE,
    "scene": BASE + ["scene"],
    "frame": BASE + ["scene", "frame"],
    "api": BASE + ["scene", "frame", "api"],
    "blocks": BASE + ["scene", "frame", "api", "blocks"],
    "reference": BASE + ["scene", "frame", "reference"],
    "run": BASE + ["scene", "frame", "api", "reference", "run"],
    "sweep": BASE + ["scene", "frame", "api", "reference", "run", "sweep"],
    "synth": BASE + ["scene", "frame", "api", "reference", "run", "synth"],
    "report": BASE + ["report"],
    "view": BASE + ["scene", "frame", "api", "reference", "run", "view"],
    "cli": BASE + ["scene", "frame", "api", "reference", "run", "sweep", "synth", "report", "view"],
    "method": BASE + ["scene", "frame", "api", "blocks"],
    "method_tests": BASE + ["scene", "frame", "api", "blocks", "reference", "run", "sweep", "synth", "report"],
}
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.M)
SOURCES = (".cpp", ".hpp", ".h", ".cc")


def method_names(root):
    methods = os.path.join(root, "methods")
    if not os.path.isdir(methods):
        return []
    return sorted(d for d in os.listdir(methods) if os.path.isfile(os.path.join(methods, d, "CMakeLists.txt")))


def files_under(folder, suffixes):
    for dirpath, _, names in os.walk(folder):
        for name in sorted(names):
            if name.endswith(suffixes):
                yield os.path.join(dirpath, name)


def part_of(root, path):
    """('method', name) for files of a method, (layer, None) for harness files, None otherwise."""
    rel = os.path.relpath(path, root).split(os.sep)
    if rel[0] == "methods" and len(rel) > 3 and rel[2] == "tests":
        return ("method_tests", rel[1])   # a method's tests may use the whole framework
    if rel[0] == "methods" and len(rel) > 2:
        return ("method", rel[1])
    if rel[0] == "harness" and len(rel) > 2:
        return (rel[1], None)
    return None


def check_includes(root, problems):
    methods = set(method_names(root))
    for top in ("harness", "methods"):
        for path in files_under(os.path.join(root, top), SOURCES):
            part = part_of(root, path)
            if part is None or part[0] not in ALLOWED:
                continue
            layer, method = part
            rel = os.path.relpath(path, root)
            text = open(path, encoding="utf-8", errors="replace").read()
            for target in INCLUDE.findall(text):
                if target.startswith("caustics/"):
                    used = target.split("/")[1]
                    if used not in ALLOWED[layer]:
                        who = f"method {method}" if method else f"layer {layer}"
                        problems.append(f"{rel}: includes <{target}>; {who} may include only "
                                        f"{', '.join('caustics/' + a for a in ALLOWED[layer])}")
                elif "/" in target or target.endswith(".hpp"):
                    # A quoted include resolves beside the file: it must stay inside its own part.
                    resolved = os.path.normpath(os.path.join(os.path.dirname(path), target))
                    if not os.path.exists(resolved):
                        continue   # a system or library header
                    owner = part_of(root, resolved)
                    # A method's tests may include the method's own headers.
                    same = owner == part or (method is not None and owner is not None and owner[1] == method)
                    if not same:
                        problems.append(f"{rel}: includes \"{target}\" from another part ({os.path.relpath(resolved, root)}); "
                                        "use <caustics/LAYER/...> for a public header")
            if method is None:
                for name in methods:
                    if re.search(r"\b" + re.escape(name) + r"\b", text):
                        problems.append(f"{rel}: names the method '{name}'; harness/ must not name a method")
    for path in files_under(os.path.join(root, "harness"), ("CMakeLists.txt", ".cmake")):
        text = open(path, encoding="utf-8").read()
        for name in methods:
            if re.search(r"\b" + re.escape(name) + r"\b", text):
                problems.append(f"{os.path.relpath(path, root)}: names the method '{name}'")


def check_links(links_file, problems):
    for line in open(links_file, encoding="utf-8"):
        if ":" not in line:
            continue
        target, deps = line.split(":", 1)
        target = target.strip()
        part = "method" if target.startswith("method_") else target[len("caustics_"):]
        if part not in ALLOWED:
            continue
        for dep in deps.split():
            if dep.startswith("method_"):
                problems.append(f"{target} links the method target {dep}; methods never depend on each other")
                continue
            layer = dep[len("caustics_"):]
            if layer in ALLOWED and layer not in ALLOWED[part]:
                problems.append(f"{target} links caustics_{layer}; it may link only "
                                f"{', '.join('caustics_' + a for a in ALLOWED[part] if a != part)}")


def check(root, links_file):
    problems = []
    check_includes(root, problems)
    check_links(links_file, problems)
    return problems


def self_test():
    planted = {
        "harness/frame/bad_frame.cpp": "#include <caustics/reference/reference.hpp>\n",
        "harness/run/names_method.cpp": "// calls the demo_method code\n",
        "harness/report/uses_block.cpp": "#include <caustics/blocks/fft/fft.hpp>\n",
        "methods/demo_method/CMakeLists.txt": "caustics_add_method(demo_method)\n",
        "methods/demo_method/demo.cpp": "#include <caustics/sweep/sweep.hpp>\n#include \"../other_method/other.hpp\"\n",
        "methods/other_method/CMakeLists.txt": "caustics_add_method(other_method)\n",
        "methods/other_method/other.hpp": "#pragma once\n",
        "methods/other_method/ok.cpp": "#include \"other.hpp\"\n#include <caustics/blocks/fft/fft.hpp>\n",
        "methods/other_method/tests/test_ok.cpp": "#include \"../other.hpp\"\n#include <caustics/reference/reference.hpp>\n",
    }
    links = "caustics_frame: caustics_scene caustics_util caustics_reference\nmethod_demo_method: caustics_api caustics_run\n" \
            "method_other_method: caustics_api caustics_blocks caustics_frame caustics_scene caustics_util\n"
    with tempfile.TemporaryDirectory() as tmp:
        for rel, text in planted.items():
            path = os.path.join(tmp, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            open(path, "w").write(text)
        links_file = os.path.join(tmp, "links.txt")
        open(links_file, "w").write(links)
        problems = check(tmp, links_file)
    expected = [
        "bad_frame.cpp: includes <caustics/reference/reference.hpp>",
        "names_method.cpp: names the method 'demo_method'",
        "uses_block.cpp: includes <caustics/blocks/fft/fft.hpp>",
        "demo.cpp: includes <caustics/sweep/sweep.hpp>",
        "demo.cpp: includes \"../other_method/other.hpp\" from another part",
        "caustics_frame links caustics_reference",
        "method_demo_method links caustics_run",
    ]
    missing = [e for e in expected if not any(e in p for p in problems)]
    extra = [p for p in problems if not any(e in p for e in expected)]
    for m in missing:
        print("not reported:", m)
    for p in extra:
        print("reported wrongly:", p)
    print(f"self-test: {len(expected) - len(missing)} of {len(expected)} planted violations reported, "
          f"{len(extra)} false reports")
    return 1 if missing or extra else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) != 3:
        print(__doc__)
        return 2
    problems = check(argv[1], argv[2])
    for p in problems:
        print(p)
    print(f"layering: {len(problems)} violation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
