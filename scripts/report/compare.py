"""Two sweeps compared run by run: `caustics compare BASE NEW` (harness/report/report_front.cpp) runs this.

Runs are matched by scene, frame, method and parameters (results.jsonl of each folder; merged shard folders
too). Per pair:
  time   the ratio of the median frame times, and a two-sided Mann-Whitney U test on the timed frames'
         samples (time_ms.samples / frame_ms.samples): SLOWER or FASTER when p < alpha and the ratio is
         beyond 1 +- time_threshold, else SAME (the test alone would flag a 0.1 % change on many samples);
  error  the difference of the net errors (receiver; fitted for relative output) with an interval from the
         two runs' replica intervals (half-widths added in quadrature; 0 against an exact truth): WORSE or
         BETTER when the interval excludes 0 and the change is beyond error_threshold of the base's error.
Writes OUT/compare.md, OUT/compare.csv, OUT/compare_time_vs_error.png and OUT/compare.html (the same as one
self-contained page; each file written to a temporary name and renamed). Exit status: 0; 3 with --fail-on-regression when a pair is SLOWER or WORSE; 2 for bad input
(one line on stderr, nothing written).
"""
import argparse
import json
import math
import os
import sys
import tempfile

import numpy as np

from load import machine_parts

KEY_FIELDS = ("scene", "frame", "method")


class InputProblem(Exception):
    pass


def read_runs(directory):
    """{key: row} of a sweep folder's finished runs; the manifest ({} where absent)."""
    path = os.path.join(directory, "results.jsonl")
    if not os.path.isfile(path):
        raise InputProblem(f"{directory}: not a sweep folder (no results.jsonl); valid: a folder `caustics sweep` wrote")
    runs = {}
    with open(path) as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                row = json.loads(line)
            except ValueError:
                raise InputProblem(f"{path}:{number}: not a JSON line; valid: the results.jsonl a sweep writes")
            if not isinstance(row, dict) or any(k not in row for k in KEY_FIELDS):
                raise InputProblem(f"{path}:{number}: no scene, frame and method; valid: the results.jsonl a sweep writes")
            runs[run_key(row)] = row
    if not runs:
        raise InputProblem(f"{path}: holds no run; valid: a sweep with at least one finished run")
    manifest = {}
    manifest_path = os.path.join(directory, "manifest.json")
    if os.path.isfile(manifest_path):
        try:
            with open(manifest_path) as f:
                manifest = json.load(f)
        except ValueError:
            raise InputProblem(f"{manifest_path}: not JSON; valid: the manifest.json a sweep writes")
    return runs, manifest


def run_key(row):
    params = json.dumps(row.get("params") or {}, sort_keys=True)
    return (row["scene"], int(row["frame"]), row["method"], params)


def mann_whitney_p(a, b):
    """Two-sided p value of the Mann-Whitney U test (normal approximation with the tie correction and a
    continuity correction); 1 where either side has fewer than 2 samples or all values tie."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    n1, n2 = len(a), len(b)
    if n1 < 2 or n2 < 2:
        return 1.0
    values = np.concatenate([a, b])
    order = np.argsort(values, kind="mergesort")
    ranks = np.empty(len(values))
    sorted_values = values[order]
    i = 0
    tie_term = 0.0
    while i < len(values):
        j = i
        while j + 1 < len(values) and sorted_values[j + 1] == sorted_values[i]:
            j += 1
        ranks[order[i:j + 1]] = 0.5 * (i + j) + 1.0
        t = j - i + 1
        tie_term += t ** 3 - t
        i = j + 1
    u1 = ranks[:n1].sum() - n1 * (n1 + 1) / 2.0
    n = n1 + n2
    variance = n1 * n2 / 12.0 * ((n + 1) - tie_term / (n * (n - 1)))
    if variance <= 0.0:
        return 1.0
    z = (abs(u1 - n1 * n2 / 2.0) - 0.5) / math.sqrt(variance)
    return max(0.0, min(1.0, math.erfc(max(z, 0.0) / math.sqrt(2.0))))


def samples_of(row):
    for key in ("frame_ms", "time_ms"):
        s = (row.get(key) or {}).get("samples")
        if isinstance(s, list) and s:
            return [float(x) for x in s if x is not None]
    return []


def median_of(row):
    for key in ("frame_ms", "time_ms"):
        m = (row.get(key) or {}).get("median")
        if isinstance(m, (int, float)):
            return float(m)
    return math.nan


def error_of(row):
    """(error, half-width of its interval) of the receiver's net error of the kind the method is judged by."""
    e = ((row.get("error") or {}).get("receiver")) or {}
    prefix = "nrmse_net" if row.get("radiometric", True) else "nrmse_fit_net"
    value = e.get(prefix)
    if value is None:
        value = e.get("nrmse" if row.get("radiometric", True) else "nrmse_fit")
        return (float(value), 0.0) if value is not None else (math.nan, math.nan)
    lo, hi = e.get(prefix + "_lo"), e.get(prefix + "_hi")
    half = 0.5 * (float(hi) - float(lo)) if lo is not None and hi is not None else 0.0
    return float(value), half


def compare_pair(base, new, alpha, time_threshold, error_threshold):
    out = {"scene": base["scene"], "frame": base["frame"], "method": base["method"],
           "params": json.dumps(base.get("params") or {}, sort_keys=True),
           "base_status": base.get("status"), "new_status": new.get("status")}
    sb, sn = samples_of(base), samples_of(new)
    if sb and sn:
        mb, mn = float(np.median(sb)), float(np.median(sn))
        ratio = mn / mb if mb > 0 else math.nan
        p = mann_whitney_p(sb, sn)
        out.update(base_ms=mb, new_ms=mn, time_ratio=ratio, time_p=p, base_samples=len(sb), new_samples=len(sn))
        if p < alpha and ratio > 1.0 + time_threshold:
            out["time"] = "SLOWER"
        elif p < alpha and ratio < 1.0 - time_threshold:
            out["time"] = "FASTER"
        else:
            out["time"] = "SAME"
    else:
        # A sweep from before the samples were kept: the ratio of the medians, untested.
        mb, mn = median_of(base), median_of(new)
        out.update(base_ms=mb, new_ms=mn, time_ratio=mn / mb if mb > 0 else math.nan, time_p=math.nan, time="-")
    eb, hb = error_of(base)
    en, hn = error_of(new)
    if math.isfinite(eb) and math.isfinite(en):
        diff = en - eb
        half = math.sqrt(hb * hb + hn * hn)
        out.update(base_error=eb, new_error=en, error_diff=diff, error_diff_lo=diff - half, error_diff_hi=diff + half,
                   error_ratio=en / eb if eb > 0 else math.nan)
        beyond = abs(diff) > error_threshold * max(eb, 1e-12)
        if diff - half > 0 and beyond:
            out["error"] = "WORSE"
        elif diff + half < 0 and beyond:
            out["error"] = "BETTER"
        else:
            out["error"] = "SAME"
    else:
        out.update(base_error=math.nan, new_error=math.nan, error_diff=math.nan, error_diff_lo=math.nan,
                   error_diff_hi=math.nan, error_ratio=math.nan, error="-")
    return out


def manifest_warnings(mb, mn):
    """Differences between the two sides that make their times hard to compare."""
    warnings = []
    hb, hn = mb.get("host") or {}, mn.get("host") or {}
    for label, a, b in (("CPU", hb.get("cpu"), hn.get("cpu")), ("cores", hb.get("cores"), hn.get("cores")),
                        ("threads", mb.get("threads"), mn.get("threads")),
                        ("build type", mb.get("build_type"), mn.get("build_type"))):
        if a is not None and b is not None and a != b:
            warnings.append(f"{label} differs: {a} (base) against {b} (new)")
    for side, m in (("base", mb), ("new", mn)):
        if any(p.get("loaded") for p in machine_parts(m)):
            warnings.append(f"the {side} sweep started on a busy machine (manifest.json machine.loaded)")
    return warnings


def _fmt(x, spec):
    return format(x, spec) if isinstance(x, (int, float)) and math.isfinite(x) else "-"


def markdown(pairs, only_base, only_new, mb, mn, warnings, args):
    lines = ["# Sweep comparison", "",
             f"Base: `{args.base}` (commit {mb.get('git_commit', '?')}); new: `{args.new}` (commit "
             f"{mn.get('git_commit', '?')}). Time: median frame time ratio, Mann-Whitney U on the timed frames, "
             f"alpha {args.alpha}, threshold {args.time_threshold:.0%}. Error: net error difference with its "
             f"interval, threshold {args.error_threshold:.0%} of the base's.", ""]
    for w in warnings:
        lines.append(f"**Warning:** {w}.")
    if warnings:
        lines.append("")
    def tally(field):
        counts = {}
        for p in pairs:
            counts[p[field]] = counts.get(p[field], 0) + 1
        return ", ".join(f"{v} {k if k != '-' else 'not compared'}" for k, v in sorted(counts.items()))

    lines.append(f"{len(pairs)} matched runs. Time: {tally('time')}. Error: {tally('error')}.")
    varied = varied_parameters(pairs)
    lines += ["", "| scene | frame | method | parameters varied | time | ratio | p | error | base | new | diff interval |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for p in pairs:
        params = ", ".join(f"{k}={v}" for k, v in json.loads(p["params"]).items() if k in varied[p["method"]])
        lines.append(f"| {p['scene']} | {p['frame']} | {p['method']} | {params} | {p['time']} | "
                     f"{_fmt(p['time_ratio'], '.3f')} | {_fmt(p['time_p'], '.2g')} | {p['error']} | "
                     f"{_fmt(p['base_error'], '.4g')} | {_fmt(p['new_error'], '.4g')} | "
                     f"[{_fmt(p['error_diff_lo'], '.3g')}, {_fmt(p['error_diff_hi'], '.3g')}] |")
    for label, keys in (("Only in the base", only_base), ("Only in the new sweep", only_new)):
        if keys:
            lines += ["", f"{label} ({len(keys)}):", ""]
            lines += [f"- {k[0]} frame {k[1]} {k[2]} {k[3]}" for k in keys]
    return "\n".join(lines) + "\n"


def varied_parameters(pairs):
    """Per method, the parameters whose values differ between its matched runs (the table shows only those)."""
    values = {}
    for p in pairs:
        for k, v in json.loads(p["params"]).items():
            values.setdefault(p["method"], {}).setdefault(k, set()).add(json.dumps(v))
    return {m: {k for k, vs in params.items() if len(vs) > 1} for m, params in values.items()}


CSV_COLUMNS = ("scene", "frame", "method", "params", "base_status", "new_status", "time", "base_ms", "new_ms",
               "time_ratio", "time_p", "error", "base_error", "new_error", "error_diff", "error_diff_lo",
               "error_diff_hi", "error_ratio")


def csv_text(pairs):
    import csv
    import io

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for p in pairs:
        w.writerow({k: ("" if isinstance(p.get(k), float) and not math.isfinite(p[k]) else p.get(k)) for k in CSV_COLUMNS})
    return buf.getvalue()


def write_atomically(path, data, binary=False):
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix=".compare.")
    with os.fdopen(fd, "wb" if binary else "w") as f:
        f.write(data)
    os.replace(tmp, path)


def figure(pairs, path):
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4.5))
    colours = {"SLOWER": "tab:red", "FASTER": "tab:green", "SAME": "tab:grey", "-": "tab:grey"}
    for p in pairs:
        x, y = p["time_ratio"], p["error_ratio"]
        if math.isfinite(x) and math.isfinite(y) and y > 0:
            ax.scatter(x, y, color=colours.get(p["time"], "tab:grey"),
                       marker="^" if p["error"] == "WORSE" else ("v" if p["error"] == "BETTER" else "o"))
    ax.axvline(1.0, color="k", lw=0.5)
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frame time ratio (new / base)")
    ax.set_ylabel("net error ratio (new / base)")
    ax.set_title("Each matched run: red slower, green faster; triangles: error worse / better")
    buf = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buf, format="png", dpi=120)
    plt.close(fig)
    write_atomically(path, buf.getvalue(), binary=True)
    return buf.getvalue()


def html_page(pairs, only_base, only_new, mb, mn, warnings, args, figure_png):
    """compare.html: the same comparison as one self-contained page (the figure embedded, the table sortable,
    each run's parameters on hover), with report.html's style and script."""
    import html

    from html_report import SCRIPT, STYLE, png_uri

    esc = html.escape
    varied = varied_parameters(pairs)
    rows = []
    for p in pairs:
        params = json.loads(p["params"])
        shown = ", ".join(f"{k}={v}" for k, v in params.items() if k in varied[p["method"]])
        tip = esc(", ".join(f"{k}={v}" for k, v in params.items()))
        cells = [p["scene"], p["frame"], p["method"]]
        rows.append("<tr>" + "".join(f'<td class="text">{esc(str(c))}</td>' for c in cells) +
                    f'<td class="text" title="{tip}">{esc(shown)}</td>' +
                    "".join(f"<td>{esc(str(v))}</td>" for v in (
                        p["time"], _fmt(p["time_ratio"], ".3f"), _fmt(p["time_p"], ".2g"), p["error"],
                        _fmt(p["base_error"], ".4g"), _fmt(p["new_error"], ".4g"))) + "</tr>")
    head = "".join(f"<th>{h}</th>" for h in ("scene", "frame", "method", "parameters varied", "time", "ratio", "p",
                                             "error", "base error", "new error"))
    unmatched = "".join(f"<li>{esc(label)}: {esc(str(k[0]))} frame {k[1]} {esc(k[2])} {esc(k[3])}</li>"
                        for label, keys in (("only in the base", only_base), ("only in the new sweep", only_new))
                        for k in keys)
    return ("<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Sweep comparison</title>"
            f"<style>{STYLE}</style><script>{SCRIPT}</script></head><body><h1>Sweep comparison</h1>"
            f"<p>Base: <code>{esc(args.base)}</code> (commit {esc(str(mb.get('git_commit', '?')))}); new: "
            f"<code>{esc(args.new)}</code> (commit {esc(str(mn.get('git_commit', '?')))}). Alpha {args.alpha}, time "
            f"threshold {args.time_threshold:.0%}, error threshold {args.error_threshold:.0%}.</p>"
            + "".join(f"<p><strong>Warning:</strong> {esc(w)}.</p>" for w in warnings)
            + f'<figure><img alt="time ratio against error ratio" src="{png_uri(figure_png)}"></figure>'
            f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
            + (f"<ul>{unmatched}</ul>" if unmatched else "") + "</body></html>\n")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("base")
    ap.add_argument("new")
    ap.add_argument("--out")
    ap.add_argument("--alpha", type=float, default=0.01)
    ap.add_argument("--time-threshold", type=float, default=0.05)
    ap.add_argument("--error-threshold", type=float, default=0.01)
    ap.add_argument("--fail-on-regression", action="store_true")
    args = ap.parse_args(argv)
    try:
        if not 0.0 < args.alpha < 1.0:
            raise InputProblem(f"--alpha: {args.alpha}; valid: a number between 0 and 1")
        for name in ("time_threshold", "error_threshold"):
            v = getattr(args, name)
            if not (math.isfinite(v) and 0.0 <= v <= 10.0):
                raise InputProblem(f"--{name.replace('_', '-')}: {v}; valid: a number from 0 to 10")
        base, mb = read_runs(args.base)
        new, mn = read_runs(args.new)
    except InputProblem as e:
        print(f"caustics: error: {e}", file=sys.stderr)
        return 2
    out = args.out or os.path.join(args.new, "compare")
    os.makedirs(out, exist_ok=True)
    keys = sorted(set(base) & set(new))
    pairs = [compare_pair(base[k], new[k], args.alpha, args.time_threshold, args.error_threshold) for k in keys]
    only_base = sorted(set(base) - set(new))
    only_new = sorted(set(new) - set(base))
    warnings = manifest_warnings(mb, mn)
    write_atomically(os.path.join(out, "compare.md"), markdown(pairs, only_base, only_new, mb, mn, warnings, args))
    write_atomically(os.path.join(out, "compare.csv"), csv_text(pairs))
    png = figure(pairs, os.path.join(out, "compare_time_vs_error.png"))
    write_atomically(os.path.join(out, "compare.html"),
                     html_page(pairs, only_base, only_new, mb, mn, warnings, args, png))
    regressions = [p for p in pairs if p["time"] == "SLOWER" or p["error"] == "WORSE"]
    for w in warnings:
        print(f"compare: warning: {w}", file=sys.stderr)
    print(f"compare: {len(pairs)} matched runs, {len(regressions)} slower or worse, {len(only_base)} only in the base, "
          f"{len(only_new)} only in the new sweep; wrote {os.path.join(out, 'compare.md')}")
    return 3 if args.fail_on_regression and regressions else 0


if __name__ == "__main__":
    sys.exit(main())
