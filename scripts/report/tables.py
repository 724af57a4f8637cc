"""Summary tables (Markdown and LaTeX booktabs): equal-time, equal-quality and paper-setting columns."""
import os

import numpy as np

from load import ok_runs


def _fmt(value, digits=3):
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "--"
    return f"{value:.{digits}g}"


def summary_rows(frame, scene, time_budget_ms, error_target, paper_settings):
    runs = ok_runs(frame[frame["scene"] == scene])
    rows = []
    for label, group in runs.groupby("label"):
        method = group["method"].iloc[0]
        within = group[group["time_ms_median"] <= time_budget_ms]
        best_error = float(within["error"].min()) if not within.empty else None
        reaching = group[group["error"] <= error_target]
        time_to_target = float(reaching["time_ms_median"].min()) if not reaching.empty else None
        paper = group
        for key, value in (paper_settings.get(method) or {}).items():
            column = f"param.{key}"
            if column in paper:
                paper = paper[paper[column].astype(str) == str(value)]
        paper_fps = float(paper["fps"].median()) if paper_settings.get(method) and not paper.empty else None
        paper_error = float(paper["error"].median()) if paper_settings.get(method) and not paper.empty else None
        rows.append({"method": label, "runs": len(group), "best_error_in_budget": best_error,
                     "time_to_target_ms": time_to_target, "paper_fps": paper_fps, "paper_error": paper_error})
    return rows


def _write(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def write_tables(frame, scene, directory, time_budget_ms, error_target, paper_settings, context):
    rows = summary_rows(frame, scene, time_budget_ms, error_target, paper_settings)
    if not rows:
        return None
    runs = ok_runs(frame[frame["scene"] == scene])
    noise = float(runs["noise_nrmse"].median()) if "noise_nrmse" in runs and not runs.empty else float("nan")
    caption = (f"{scene}: best nrmse within {time_budget_ms:g} ms (equal time), time to reach nrmse "
               f"{error_target:g} (equal quality), and fps / nrmse at the papers' settings. Methods marked "
               f"(fit) are non-radiometric: their error is measured after a least-squares scale fit. "
               f"Reference noise floor nrmse {_fmt(noise)}. {context}")
    header = ["method", "runs", f"best nrmse <= {time_budget_ms:g} ms", f"ms to nrmse <= {error_target:g}",
              "paper fps", "paper nrmse"]
    keys = ["method", "runs", "best_error_in_budget", "time_to_target_ms", "paper_fps", "paper_error"]
    cells = [[str(r[k]) if k in ("method", "runs") else _fmt(r[k]) for k in keys] for r in rows]

    md = [f"Table: {caption}", "", "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    md += ["| " + " | ".join(c) + " |" for c in cells]
    _write(os.path.join(directory, f"summary_{scene}.md"), "\n".join(md) + "\n")

    def tex(s):
        return (s.replace("\\", "\\textbackslash{}").replace("_", "\\_").replace("%", "\\%")
                .replace("&", "\\&").replace("#", "\\#").replace("<=", "$\\le$"))

    lines = ["\\begin{table}[t]", "\\centering", f"\\caption{{{tex(caption)}}}",
             f"\\label{{tab:summary-{scene}}}", "\\begin{tabular}{l" + "r" * (len(header) - 1) + "}",
             "\\toprule", " & ".join(tex(h) for h in header) + " \\\\", "\\midrule"]
    lines += [" & ".join(tex(c) for c in row) + " \\\\" for row in cells]
    lines += ["\\bottomrule", "\\end{tabular}", "\\end{table}"]
    _write(os.path.join(directory, f"summary_{scene}.tex"), "\n".join(lines) + "\n")
    return "\n".join(md)
