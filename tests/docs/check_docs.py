#!/usr/bin/env python3
"""Checks that the documentation stays a front door with links that lead somewhere.

  check_docs.py REPO_ROOT [--readme PATH]   exit 1 listing every problem, 0 if there is none
  check_docs.py --self-test                 plants one problem of each kind in a temporary tree and
                                            checks that every one is reported

Rules:
  - README.md has at most 150 lines (--readme checks another file in its place, with links resolved
    from the folder of README.md);
  - every relative Markdown link or image ([text](path), ![alt](path), [label]: path) in README.md,
    docs/*.md, methods/*/README.md, scenes/README.md and every other Markdown file of the repository
    names a file or folder that exists inside the repository (http(s), mailto and other URLs and pure
    #anchors are not checked; a path's #anchor is dropped);
  - no text file of the repository (git ls-files: tracked, and new files git does not ignore) cites the
    design document that lived outside the repository, by its old name or through the sibling folder.
    The repository's own design document is docs/design.md.

Standard library only.
"""
import os
import re
import subprocess
import sys
import tempfile
import urllib.parse

README_MAX_LINES = 150
# Spelled in pieces so that this file does not match itself.
FORBIDDEN = ["DESIGN" + ".md", ".." + "/shared"]

FENCE = re.compile(r"^\s*(```|~~~)")
INLINE_CODE = re.compile(r"(`+)(?:(?!\1).)+?\1")
# [text](target) and ![alt](target); text may hold one level of brackets (an image inside a link).
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|[^)\s]+)(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^)]*\)))?\s*\)")
REFERENCE_DEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def markdown_targets(text):
    """(line number, target) of every link and image outside code blocks and code spans."""
    out = []
    in_fence = None
    for number, line in enumerate(text.splitlines(), 1):
        m = FENCE.match(line)
        if m:
            if in_fence is None:
                in_fence = m.group(1)
            elif m.group(1) == in_fence:
                in_fence = None
            continue
        if in_fence is not None:
            continue
        line = INLINE_CODE.sub("", line)
        for m in INLINE_LINK.finditer(line):
            out.append((number, m.group(1)))
        m = REFERENCE_DEF.match(line)
        if m:
            out.append((number, m.group(1)))
    return out


def check_target(root, md_dir, target):
    """None when the target is fine (or not checked), else what is wrong."""
    t = target.strip()
    if t.startswith("<") and t.endswith(">"):
        t = t[1:-1].strip()
    if not t or t.startswith("#") or SCHEME.match(t) or t.startswith("//"):
        return None
    path = urllib.parse.unquote(t.split("#", 1)[0].split("?", 1)[0])
    if not path:
        return None
    base = root if path.startswith("/") else md_dir
    resolved = os.path.realpath(os.path.join(base, path.lstrip("/")))
    real_root = os.path.realpath(root)
    if resolved != real_root and not resolved.startswith(real_root + os.sep):
        return "points outside the repository"
    if not os.path.exists(resolved):
        return "no such file"
    return None


def repository_files(root):
    """Relative paths of the repository's files: git's tracked files and new files it does not ignore;
    without git, every file outside .git/ and build folders."""
    try:
        out = subprocess.run(["git", "-C", root, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                             check=True, capture_output=True).stdout
        return sorted({p for p in out.decode("utf-8", "surrogateescape").split("\0") if p})
    except (OSError, subprocess.CalledProcessError):
        files = []
        for dirpath, dirnames, filenames in os.walk(root):
            rel_dir = os.path.relpath(dirpath, root)
            dirnames[:] = [d for d in dirnames
                           if d != ".git" and not (rel_dir == "." and (d.startswith("build") or d == "results"))]
            files.extend(os.path.normpath(os.path.join(rel_dir, f)) for f in filenames)
        return sorted(files)


def markdown_files(root, files):
    """The Markdown files to check: the named ones, then every other .md file of the repository."""
    named = ["README.md", "scenes/README.md"]
    for folder, pattern in (("docs", None), ("methods", "README.md")):
        top = os.path.join(root, folder)
        if not os.path.isdir(top):
            continue
        for entry in sorted(os.listdir(top)):
            if pattern is None and entry.endswith(".md"):
                named.append(f"{folder}/{entry}")
            elif pattern is not None and os.path.isfile(os.path.join(top, entry, pattern)):
                named.append(f"{folder}/{entry}/{pattern}")
    seen = []
    for rel in named + [f for f in files if f.endswith(".md")]:
        if rel not in seen and os.path.isfile(os.path.join(root, rel)):
            seen.append(rel)
    return seen


def check(root, readme=None):
    """Every problem found, as lines of text."""
    problems = []
    root = os.path.abspath(root)
    readme_path = readme or os.path.join(root, "README.md")
    try:
        with open(readme_path, encoding="utf-8") as f:
            lines = f.read().splitlines()
        if len(lines) > README_MAX_LINES:
            problems.append(f"{readme_path}: {len(lines)} lines; the front door holds at most {README_MAX_LINES} "
                            "(move the detail into docs/ and link it)")
    except OSError as e:
        problems.append(f"{readme_path}: cannot be read ({e.strerror})")

    files = repository_files(root)
    checked = markdown_files(root, files)
    for rel in checked:
        path = os.path.join(root, rel)
        md_dir = os.path.dirname(path)
        if rel == "README.md" and readme:
            path = readme   # another file in the README's place, resolved from the repository root
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        for number, target in markdown_targets(text):
            why = check_target(root, md_dir, target)
            if why:
                problems.append(f"{rel}:{number}: link '{target}' {why}")

    for rel in files:
        path = os.path.join(root, rel)
        if not os.path.isfile(path):
            continue
        try:
            with open(path, "rb") as f:
                data = f.read()
        except OSError:
            continue
        if b"\0" in data:
            continue   # binary
        text = data.decode("utf-8", "replace")
        for number, line in enumerate(text.splitlines(), 1):
            for word in FORBIDDEN:
                if word in line:
                    problems.append(f"{rel}:{number}: cites '{word}', which a clone does not have; "
                                    "cite docs/design.md (its sections keep their numbers)")
    return problems


def self_test():
    """Plants one problem of each kind and checks that each is reported, and that a clean tree passes."""
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        def write(rel, text):
            path = os.path.join(tmp, rel)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)

        write("README.md", "# x\n\n![picture](docs/p.png) [design](docs/design.md#3-views) [web](https://example.org)\n"
                           "[anchor](#x) `[code](missing.md)`\n\n```\n[fenced](missing.md)\n```\n")
        write("docs/design.md", "# d\n[back](../README.md) [method](../methods/m/README.md)\n")
        write("docs/p.png", "png")
        write("methods/m/README.md", "# m\n[design](../../docs/design.md)\n")
        write("scenes/README.md", "# s\n[ref]: ../docs/design.md\n")
        clean = check(tmp)
        if clean:
            failures.append("a clean tree was reported: " + "; ".join(clean))

        long_readme = os.path.join(tmp, "long_README.md")
        with open(long_readme, "w", encoding="utf-8") as f:
            f.write("line\n" * (README_MAX_LINES + 1))
        planted = {
            "long README": (lambda: check(tmp, readme=long_readme), "lines; the front door"),
        }
        for name, (run, expected) in planted.items():
            if not any(expected in p for p in run()):
                failures.append(f"{name}: not reported")

        cases = [
            ("broken link in docs/", "docs/extra.md", "[gone](nothing.md)\n", "docs/extra.md:1: link 'nothing.md' no such file"),
            ("broken image in a method README", "methods/m/README.md", "![i](fig.png)\n", "methods/m/README.md:1: link 'fig.png'"),
            ("broken reference definition", "scenes/README.md", "[r]: missing/file.md\n", "scenes/README.md:1: link"),
            ("link outside the repository", "docs/out.md", "[o](../../elsewhere.md)\n", "points outside the repository"),
            ("old design document", "harness/x.hpp", "// see " + FORBIDDEN[0] + " section 6\n", "harness/x.hpp:1: cites"),
            ("sibling folder", "scripts/y.py", "# " + FORBIDDEN[1] + "/assets/a.obj\n", "scripts/y.py:1: cites"),
        ]
        for name, rel, text, expected in cases:
            path = os.path.join(tmp, rel)
            before = open(path, encoding="utf-8").read() if os.path.exists(path) else None
            write(rel, text)
            found = check(tmp)
            if not any(expected in p for p in found):
                failures.append(f"{name}: expected '{expected}', got {found}")
            if before is None:
                os.remove(path)
            else:
                write(rel, before)
    for f in failures:
        print("self-test:", f, file=sys.stderr)
    print("check_docs self-test:", "FAILED" if failures else "every planted problem was reported")
    return 1 if failures else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    args = argv[1:]
    readme = None
    if "--readme" in args:
        i = args.index("--readme")
        if i + 1 >= len(args):
            print("usage: check_docs.py REPO_ROOT [--readme PATH] | --self-test", file=sys.stderr)
            return 2
        readme = os.path.abspath(args[i + 1])
        del args[i:i + 2]
    if len(args) != 1 or not os.path.isdir(args[0]):
        print("usage: check_docs.py REPO_ROOT [--readme PATH] | --self-test", file=sys.stderr)
        return 2
    problems = check(args[0], readme)
    for p in problems:
        print("check_docs:", p, file=sys.stderr)
    if problems:
        print(f"check_docs: {len(problems)} problem(s)", file=sys.stderr)
        return 1
    print("check_docs: README within its limit, every link resolves, no citation outside the repository")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
