#!/usr/bin/env python3
"""Writes DIR/report.md, DIR/figures/*.png|pdf and DIR/tables/*.tex|md from a sweep directory.

Usage: report.py DIR   (normally run through `caustics report DIR`)
Needs Debian's python3-matplotlib, python3-pandas, python3-numpy and python3-openimageio.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

try:
    import matplotlib  # noqa: F401
    import numpy  # noqa: F401
    import pandas  # noqa: F401
except ImportError as error:  # say which module is missing and where it comes from
    sys.exit(f"report: python module missing ({error.name}); install Debian's python3-{error.name} "
             f"(scripts/setup.sh does) and run with /usr/bin/python3")

import figures  # noqa: E402
import html_report  # noqa: E402
import quality  # noqa: E402
import tables  # noqa: E402
import volume  # noqa: E402
from load import machine_parts, read_manifest, read_results  # noqa: E402


def machine_line(manifest):
    """How busy the machine was (manifest.json "machine", and each resumed part's): the 1-minute load average
    at the start and end of each part, the governor, and a warning for a part that started on a busy
    machine. Empty for sweeps that did not record it."""
    parts = machine_parts(manifest)
    if not parts:
        return ""

    def state(s):
        s = s or {}
        busy, values = s.get("busy"), s.get("load_average")
        text = f"{busy:.0%} busy" if isinstance(busy, (int, float)) else "?"
        return text + (f" (load {values[0]:.2f})" if isinstance(values, list) and values else "")

    spans = "; ".join(f"{state(p.get('start'))} at the start, {state(p.get('end'))} at the end" for p in parts)
    governor = (parts[0].get("start") or {}).get("governor")
    line = f"CPUs: {spans}" + (f"; governor {governor}." if governor else ".")
    if any(p.get("loaded") for p in parts):
        line += (" **Warning: the machine was busy as the sweep started (its CPUs at least half busy with other "
                 "work): its timings are not a quiet machine's.**")
    return line


def context_line(manifest):
    host = manifest.get("host", {})
    line = (f"Machine: {host.get('cpu', '?')}, {host.get('cores', '?')} cores, "
            f"{manifest.get('threads', '?')} threads, {manifest.get('build_type', '?')} build, "
            f"commit {manifest.get('git_commit', '?')}.")
    machine = machine_line(manifest)
    return line + (" " + machine if machine else "")


def main(argv):
    if len(argv) != 2:
        sys.exit("usage: report.py SWEEP_DIR")
    sweep_dir = argv[1]
    frame = read_results(sweep_dir)
    manifest = read_manifest(sweep_dir)
    settings = (manifest.get("spec") or {}).get("report", {})
    budget = float(settings.get("time_budget_ms", 16.7))
    target = float(settings.get("error_target", 0.1))
    paper = settings.get("paper_settings", {})
    chosen = settings.get("image_settings", paper)
    fig_dir = os.path.join(sweep_dir, "figures")
    tab_dir = os.path.join(sweep_dir, "tables")
    os.makedirs(fig_dir, exist_ok=True)
    os.makedirs(tab_dir, exist_ok=True)
    context = context_line(manifest)

    out = [f"# Sweep report: {os.path.basename(os.path.abspath(sweep_dir))}", "", context, ""]
    counts = frame["status"].value_counts().to_dict()
    out.append("Runs: " + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + ".")
    out.append("Errors are receiver-map errors against the truth of the same frame (analytic closed form or "
               f"Monte Carlo reference): the {figures.NET_ERROR}, where the sweep recorded it, else the raw "
               "nrmse. Times are " + (f"per-frame: {figures.FRAME_TIME}." if figures.has_frame_time(frame)
                                      else "render times (this sweep records no per-frame cost).")
               + " Methods marked (fit) are non-radiometric and measured after a least-squares scale fit.")
    target_ratio = quality.noise_ratio_target(manifest)
    scenes = sorted(frame["scene"].unique())
    checks = [quality.scene_quality(frame, scene, target_ratio) for scene in scenes]
    flagged = [q["scene"] for q in checks if q["flagged"]]
    checked = any(q["ratio"] is not None for q in checks)
    out.append(f"Reference noise / smallest net error must stay <= {target_ratio:.3g}: "
               + (f"**flagged scenes: {', '.join(flagged)}**." if flagged else
                  "every scene meets it." if checked else "not checked, this sweep records no net errors."))
    out.append("Caveats over all ok runs: " + ", ".join(
        f"{sum(q[key] for q in checks)} {text}" for key, text in (
            ("below_reference_noise", "below the reference noise"), ("noisy_timing", "with noisy timing"),
            ("no_better_than_flat", "no better than the no-caustic baseline"))) + ".")
    out.append("")
    for scene, check in zip(scenes, checks):
        out += [f"## {scene}", ""] + quality.scene_lines(check) + [""]
        claims = quality.claim_lines(quality.claim_rows(frame, scene))
        if claims:
            out += ["Accuracy claims: each method's claimed nrmse inside its regime, the bound its runs were held "
                    "to (the claimed nrmse or half the no-caustic baseline's error, whichever is smaller) and the "
                    "worst error measured inside it on this scene (exact truths only).", ""] + claims + [""]
        made = figures.time_vs_error(frame, scene, fig_dir)
        if made:
            paths, caption = made
            out += [f"![{os.path.basename(paths[0])}](figures/{os.path.basename(paths[0])})", "", caption, ""]
        for make in (figures.error_vs_iterations, figures.fps_vs_grid):
            paths = make(frame, scene, fig_dir)
            if paths:
                out.append(f"![{os.path.basename(paths[0])}](figures/{os.path.basename(paths[0])})")
        paths = figures.image_grid(frame, scene, fig_dir, sweep_dir, chosen)
        if paths:
            out.append(f"![{os.path.basename(paths[0])}](figures/{os.path.basename(paths[0])})")
        out.append("")
        table = tables.write_tables(frame, scene, tab_dir, budget, target, paper, context)
        if table:
            out += [table, ""]
        growth = tables.write_growth_table(frame, scene, tab_dir)
        if growth:
            out += [growth, ""]
        out += volume.volume_section(frame, scene, fig_dir, tab_dir, sweep_dir)
    not_ok = frame[frame["status"] != "ok"]
    if not not_ok.empty:
        out += ["## Runs that did not complete", "", "| run | status | message |", "|---|---|---|"]
        out += [f"| {r.run_id} | {r.status} | {str(r.message).replace('|', '/')} |" for r in not_ok.itertuples()]
        out.append("")
    path = os.path.join(sweep_dir, "report.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(out) + "\n")
    os.replace(path + ".tmp", path)
    html_report.write_html(sweep_dir, frame, scenes, context, chosen, fig_dir)
    print(path)


if __name__ == "__main__":
    main(sys.argv)
