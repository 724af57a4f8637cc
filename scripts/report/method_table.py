"""The README's method table, generated from measurements rather than typed in.

Inputs:
  --drawn DIR    the conformance suite's drawn cases, one <method>.csv per method
                 (tests/test_conformance_drawn.cpp with CAUSTICS_CONFORMANCE_CSV_DIR set)
  --sweep DIR    a sweep (results.csv): each method's median frame time on --scene at its defaults
  --methods FILE `caustics list --json` (the methods' parameter defaults)
  --claims FILE  per method, the paper and the claim as stated (a specification, not a measurement)
  --readme FILE  rewrite the block between the markers below in place (else print the block)

The measured columns: cases inside the claim / cases drawn, the worst nrmse inside, the frame time.
scripts/studies/method_table.sh runs the whole chain.
"""
import argparse
import csv
import glob
import json
import math
import os
import sys
import tempfile

import pandas as pd

BEGIN = "<!-- method-table:begin (scripts/studies/method_table.sh writes this block) -->"
END = "<!-- method-table:end -->"


def read_drawn(directory):
    """{method: {"cases", "inside", "worst", "seed"}} from the drawn suite's CSVs."""
    out = {}
    for path in sorted(glob.glob(os.path.join(directory, "*.csv"))):
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            continue
        method = rows[0]["method"]
        inside = [r for r in rows if r["refused"] == "0" and r["inside"] == "1"]
        errors = [float(r["nrmse"]) for r in inside if r["nrmse"] not in ("", "nan")]
        seeds = {r["seed"] for r in rows}
        if len(seeds) != 1:
            raise ValueError(f"{path}: cases of several seeds ({', '.join(sorted(seeds))})")
        out[method] = {"cases": len(rows), "inside": len(inside), "worst": max(errors) if errors else math.nan,
                       "seed": seeds.pop()}
    return out


def defaults_of(methods_json):
    """{method: {param: default}} from `caustics list --json`."""
    return {m["name"]: {p["name"]: p["default"] for p in m["params"]} for m in methods_json["methods"]}


def _same(value, default):
    if isinstance(default, bool):
        return str(value).strip().lower() in (("true", "1") if default else ("false", "0"))
    if isinstance(default, (int, float)):
        try:
            return math.isclose(float(value), float(default), rel_tol=1e-9, abs_tol=1e-12)
        except (TypeError, ValueError):
            return False
    return str(value) == str(default)


def default_frame_ms(results, method, defaults, scene):
    """The median frame time of `method` on `scene` at its default parameters (NaN where the sweep has no
    such run). A parameter the sweep did not record (no column, or empty) counts as the default."""
    runs = results[(results["method"] == method) & (results["scene"] == scene) & (results["status"] == "ok")]
    for _, run in runs.iterrows():
        if all(pd.isna(run.get(f"param.{k}")) or _same(run.get(f"param.{k}"), v) for k, v in defaults.items()):
            per_frame = pd.to_numeric(pd.Series([run.get("frame_ms_median"), run.get("time_ms_median")]),
                                      errors="coerce").dropna()
            return float(per_frame.iloc[0]) if len(per_frame) else math.nan
    return math.nan


def sweep_name(directory):
    """How the table names its sweep: the spec it ran and the machine (manifest.json), else the folder."""
    try:
        with open(os.path.join(directory, "manifest.json")) as f:
            m = json.load(f)
        host = m.get("host", {})
        return (f"the sweep `{m['spec_path']}` ({m.get('build_type', '?')}, {m.get('threads', '?')} threads on "
                f"{host.get('cores', '?')} cores of {host.get('cpu', '?')})")
    except (OSError, ValueError, KeyError):
        return f"`{os.path.basename(os.path.normpath(directory))}`"


def _ms(x):
    if not math.isfinite(x):
        return "-"
    return f"{x:.1f} ms" if x >= 1.0 else f"{x:.2f} ms"


def table(drawn, claims, frame_ms, scene, sweep_name):
    seeds = {d["seed"] for d in drawn.values()}
    counts = {d["cases"] for d in drawn.values()}
    lines = [BEGIN,
             f"On {'/'.join(str(c) for c in sorted(counts))} drawn cases (seed {', '.join(sorted(seeds))}); "
             f"frame time: the median on `{scene}` at the defaults, from {sweep_name}:",
             "",
             f"| method | paper | claim (nrmse; regime) | inside | worst inside | frame on `{scene}` |",
             "|---|---|---|---|---|---|"]
    for method in claims:
        c, d = claims[method], drawn.get(method)
        inside = f"{d['inside']} / {d['cases']}" if d else "-"
        worst = f"{d['worst']:.2g}" if d and math.isfinite(d["worst"]) else "-"
        lines.append(f"| [{method}](methods/{method}/README.md) | {c['paper']} | {c['claim']} | {inside} | {worst} | "
                     f"{_ms(frame_ms.get(method, math.nan))} |")
    lines.append(END)
    return "\n".join(lines) + "\n"


def replace_block(text, block):
    """`text` with the block between the markers (inclusive) replaced; ValueError where they are missing."""
    start, end = text.find(BEGIN), text.find(END)
    if start < 0 or end < start:
        raise ValueError("the method-table markers are missing")
    rest = text[end + len(END):].lstrip("\n")
    return text[:start] + block + ("\n" + rest if rest else "")


def write_atomically(path, text):
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".method_table.")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--drawn", required=True)
    ap.add_argument("--sweep", required=True)
    ap.add_argument("--methods", required=True)
    ap.add_argument("--claims", required=True)
    ap.add_argument("--scene", default="sine")
    ap.add_argument("--readme")
    a = ap.parse_args(argv)
    try:
        drawn = read_drawn(a.drawn)
        if not drawn:
            raise ValueError(f"{a.drawn}: no <method>.csv of drawn cases")
        with open(a.claims) as f:
            claims = json.load(f)
        with open(a.methods) as f:
            defaults = defaults_of(json.load(f))
        results = pd.read_csv(os.path.join(a.sweep, "results.csv"))
        for key in claims:
            if key not in defaults:
                raise ValueError(f"{a.claims}: '{key}' is not a registered method (valid: {', '.join(defaults)})")
        frame_ms = {m: default_frame_ms(results, m, defaults[m], a.scene) for m in claims}
        block = table(drawn, claims, frame_ms, a.scene, sweep_name(a.sweep))
        if a.readme:
            with open(a.readme) as f:
                text = f.read()
            write_atomically(a.readme, replace_block(text, block))
        else:
            sys.stdout.write(block)
    except (OSError, ValueError, KeyError) as e:
        print(f"method_table: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
