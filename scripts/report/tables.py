"""Summary tables (Markdown and LaTeX booktabs): equal-time, equal-quality and paper-setting columns, with
the no-caustic baseline as a row of its own so every method's error can be read against it; and the growth
table: the fitted exponent of frame time against grid per method."""
import os

import numpy as np

from growth import growth_rows
from load import ok_runs, scene_baseline, with_settings

# Cell marks. A method that does no better than the flat interface has not produced a caustic worth
# ranking; an interval that includes 0 cannot be told from the truth at this reference's noise.
FLAT_MARK = "†"
NOISE_MARK = "‡"
FOOTNOTES = {FLAT_MARK: "no better than the no-caustic baseline",
             NOISE_MARK: "95 % interval includes 0 (below the reference noise)"}
BASELINE_ROW = "no-caustic baseline"


def _fmt(value, digits=3):
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "--"
    return f"{value:.{digits}g}"


def _marks(runs):
    """The marks that apply to a value taken from these runs (any of them flagged flags the value)."""
    return ((FLAT_MARK if runs["no_better_than_flat"].any() else "")
            + (NOISE_MARK if runs["below_reference_noise"].any() else ""))


def _cell(value, marks=""):
    return _fmt(value) + (marks if value is not None else "")


def summary_rows(frame, scene, time_budget_ms, error_target, paper_settings):
    """One row per method label (cells already formatted), then the no-caustic baseline's row."""
    runs = ok_runs(frame[frame["scene"] == scene])
    rows = []
    for label, group in runs.groupby("label"):
        method = group["method"].iloc[0]
        within = group[group["frame_ms"] <= time_budget_ms]
        best = within.loc[[within["error"].idxmin()]] if not within.empty else None
        reaching = group[group["error"] <= error_target]
        fastest = reaching.loc[[reaching["frame_ms"].idxmin()]] if not reaching.empty else None
        paper = with_settings(group, paper_settings.get(method))
        has_paper = bool(paper_settings.get(method)) and not paper.empty
        rows.append({
            "method": label, "runs": str(len(group)),
            "best_error_in_budget": _cell(float(best["error"].iloc[0]), _marks(best)) if best is not None else "--",
            "raw_error_of_best": _fmt(float(best["error_raw"].iloc[0])) if best is not None else "--",
            "time_to_target_ms": _cell(float(fastest["frame_ms"].iloc[0]), _marks(fastest))
            if fastest is not None else "--",
            "paper_fps": _fmt(float(paper["frame_fps"].median())) if has_paper else "--",
            "paper_error": _cell(float(paper["error"].median()), _marks(paper)) if has_paper else "--"})
    baseline = scene_baseline(frame, scene)
    if rows and baseline is not None:
        # An error without a time: nothing is rendered, so it sits in the error columns only.
        rows.append({"method": BASELINE_ROW, "runs": "--", "best_error_in_budget": _fmt(baseline),
                     "raw_error_of_best": "--", "time_to_target_ms": "--", "paper_fps": "--",
                     "paper_error": _fmt(baseline)})
    return rows


def _write(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def _tex(s):
    s = (s.replace("\\", "\\textbackslash{}").replace("_", "\\_").replace("%", "\\%")
         .replace("&", "\\&").replace("#", "\\#").replace("<=", "$\\le$"))
    return s.replace(FLAT_MARK, "$^\\dagger$").replace(NOISE_MARK, "$^\\ddagger$")


def write_tables(frame, scene, directory, time_budget_ms, error_target, paper_settings, context):
    rows = summary_rows(frame, scene, time_budget_ms, error_target, paper_settings)
    if not rows:
        return None
    runs = ok_runs(frame[frame["scene"] == scene])
    noise = float(runs["noise_nrmse"].median()) if not runs["noise_nrmse"].dropna().empty else float("nan")
    net = bool(runs["error_is_net"].any())
    err = "net error" if net else "nrmse"
    caption = (f"{scene}: best {err} within {time_budget_ms:g} ms (equal time), frame time to reach {err} "
               f"{error_target:g} (equal quality), and fps / {err} at the papers' settings. ")
    if net:
        caption += ("Errors are net errors (reference noise removed); the raw error of the equal-time run is "
                    "given beside it. Frame time = update + render for animated scenes. ")
    caption += ("Methods marked (fit) are non-radiometric: their error is measured after a least-squares scale "
                "fit. ")
    if rows[-1]["method"] == BASELINE_ROW:
        caption += f"The {BASELINE_ROW} row is the error of rendering no caustic (it has no time). "
    caption += f"Reference noise floor nrmse {_fmt(noise)}. {context}"
    used = [m for m in FOOTNOTES if any(m in r[k] for r in rows for k in r if k not in ("method", "runs"))]
    notes = " ".join(f"{m} {FOOTNOTES[m]}." for m in used)
    header = ["method", "runs", f"best {err} <= {time_budget_ms:g} ms", "raw error (same run)",
              f"ms to {err} <= {error_target:g}", "paper fps", f"paper {err}"]
    keys = ["method", "runs", "best_error_in_budget", "raw_error_of_best", "time_to_target_ms", "paper_fps",
            "paper_error"]
    if not net:  # without a net error the raw column would repeat the error column
        del header[3], keys[3]
    cells = [[r[k] for k in keys] for r in rows]

    md = [f"Table: {caption}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(c) + " |" for c in cells]
    if notes:
        md += ["", notes]
    _write(os.path.join(directory, f"summary_{scene}.md"), "\n".join(md) + "\n")

    lines = ["\\begin{table}[t]", "\\centering", f"\\caption{{{_tex(caption)}}}",
             f"\\label{{tab:summary-{scene}}}", "\\begin{tabular}{l" + "r" * (len(header) - 1) + "}",
             "\\toprule", " & ".join(_tex(h) for h in header) + " \\\\", "\\midrule"]
    body = [" & ".join(_tex(c) for c in row) + " \\\\" for row in cells]
    if rows[-1]["method"] == BASELINE_ROW:
        body.insert(len(body) - 1, "\\midrule")
    lines += body + ["\\bottomrule", "\\end{tabular}"]
    if notes:
        lines.append(f"\\par\\footnotesize {_tex(notes)}")
    lines.append("\\end{table}")
    _write(os.path.join(directory, f"summary_{scene}.tex"), "\n".join(lines) + "\n")
    return "\n".join(md)


def write_growth_table(frame, scene, directory):
    """How frame time grows with grid, per method and setting (growth.growth_rows): the fitted exponent s of
    frame time ~ grid^s over all grids (the fps-vs-grid figure's legend) and over the upper half, where the
    fixed per-frame costs (camera and receiver lookups, fixed-size maps) weigh least. Written as
    growth_SCENE.md and .tex; returns the Markdown, or None where no series has 3 grids."""
    rows = growth_rows(frame, scene)
    if not rows:
        return None
    caption = (f"{scene}: growth of the frame time with grid, per method (and per setting of its other varied "
               "parameters): least-squares exponent s of frame time ~ grid^s on log-log axes over all grids "
               "and over the upper half (grids at or above the median), median frame time per grid. "
               "2 means the cost follows the grid's cells of a surface, 3 those of a volume; less than the "
               "algorithm's exponent means fixed costs still weigh.")
    header = ["method", "grids", "ms at first grid", "ms at last grid", "slope, all grids", "slope, upper half"]
    cells = [[r["series"], " ".join(str(g) for g in r["grids"]), _fmt(r["ms_first"]), _fmt(r["ms_last"]),
              f"{r['slope']:.2f}", f"{r['slope_upper']:.2f} ({r['upper_grids'][0]}-{r['upper_grids'][-1]})"]
             for r in rows]
    md = [f"Table: {caption}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(c) + " |" for c in cells]
    _write(os.path.join(directory, f"growth_{scene}.md"), "\n".join(md) + "\n")
    lines = ["\\begin{table}[t]", "\\centering", f"\\caption{{{_tex(caption)}}}", f"\\label{{tab:growth-{scene}}}",
             "\\begin{tabular}{llrrrr}", "\\toprule", " & ".join(_tex(h) for h in header) + " \\\\", "\\midrule"]
    lines += [" & ".join(_tex(c) for c in row) + " \\\\" for row in cells]
    lines += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    _write(os.path.join(directory, f"growth_{scene}.tex"), "\n".join(lines) + "\n")
    return "\n".join(md)
