"""The third view, volume caustic radiance L_v (camera_volume): a time-vs-error plot, a table and an image
row per scene whose medium scatters. The receiver-map tables and figures of report.py are unchanged; these sit beside them."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from figures import _save, bare_axes  # noqa: E402
from load import numeric, read_image, run_images  # noqa: E402
from pareto import pareto_front  # noqa: E402


def volume_runs(frame, scene):
    """Ok runs of `scene` with a measured volume error: the net error where recorded, else the raw one."""
    runs = frame[(frame["scene"] == scene) & (frame["status"] == "ok")].copy()
    if runs.empty:
        return runs
    net = numeric(runs, "volume_nrmse_net")
    raw = numeric(runs, "volume_nrmse")
    runs["volume_error_is_net"] = np.isfinite(net)
    runs["volume_error"] = np.where(runs["volume_error_is_net"], net, raw)
    runs["volume_baseline"] = numeric(runs, "volume_baseline_error")
    return runs[np.isfinite(runs["volume_error"]) & np.isfinite(runs["frame_ms"])]


def _fmt(value):
    return "--" if value is None or not np.isfinite(value) else f"{value:.3g}"


def volume_table(runs, scene):
    """Markdown: per method, its lowest-error run and its fastest run, with the constant baseline."""
    net = bool(runs["volume_error_is_net"].any())
    err = "net error" if net else "nrmse"
    lines = [f"Table: {scene}, volume caustic radiance L_v (camera_volume): {err} against the reference's "
             "single-scattering view, per method its lowest-error run and its fastest run. The constant "
             "baseline is the mean radiance over the pixels the reference lights (no caustic structure).",
             "", f"| method | runs | best {err} | its ms | fastest ms | its {err} | constant baseline |",
             "|---|---|---|---|---|---|---|"]
    for label, group in runs.groupby("label"):
        best = group.loc[group["volume_error"].idxmin()]
        fast = group.loc[group["frame_ms"].idxmin()]
        baseline = float(group["volume_baseline"].median())
        lines.append(f"| {label} | {len(group)} | {_fmt(best['volume_error'])} | {_fmt(best['frame_ms'])} | "
                     f"{_fmt(fast['frame_ms'])} | {_fmt(fast['volume_error'])} | {_fmt(baseline)} |")
    return "\n".join(lines)


def volume_images(runs, scene, directory, sweep_dir):
    """Reference | each method's lowest-error run | signed difference, one shared colour scale."""
    picks = [g.loc[g["volume_error"].idxmin()] for _, g in runs.groupby("label")]
    frame_no = int(picks[0]["frame"])
    reference = read_image(os.path.join(sweep_dir, "references", f"{scene}-f{frame_no}", "reference_camera_volume.exr"))
    if reference is None:
        return None
    maps = run_images(sweep_dir, picks, "camera_volume.exr", reference.shape)
    if not maps:
        return None
    top = float(np.percentile(reference, 99.5)) or 1.0
    limit = max(float(np.percentile(np.abs(m - reference), 99.5)) for _, m in maps) or 1.0
    n = len(maps)
    fig, axes = plt.subplots(2, n + 1, figsize=(3.0 * (n + 1) + 0.8, 5.2), squeeze=False)
    im = axes[0][0].imshow(reference, cmap="inferno", vmin=0.0, vmax=top)
    axes[0][0].set_title("reference", fontsize=9)
    for i, (p, m) in enumerate(maps, start=1):
        axes[0][i].imshow(m, cmap="inferno", vmin=0.0, vmax=top)
        axes[0][i].set_title(f"{p['label']}\n{p['frame_ms']:.2f} ms", fontsize=8)
        dm = axes[1][i].imshow(m - reference, cmap="RdBu_r", vmin=-limit, vmax=limit)
        kind = "net error" if p["volume_error_is_net"] else "nrmse"
        axes[1][i].set_title(f"method - reference\n{kind} {p['volume_error']:.3f}", fontsize=8)
    bare_axes(axes)
    fig.colorbar(im, ax=list(axes[0]), shrink=0.8, label="L_v [W/(m^2 sr)]")
    fig.colorbar(dm, ax=list(axes[1]), shrink=0.8, label="signed difference [W/(m^2 sr)]")
    fig.suptitle(f"{scene}, frame {frame_no}: volume caustic radiance (camera view)", fontsize=10)
    return _save(fig, directory, f"volume_{scene}")


def _varying_params(group):
    """The parameter columns whose value differs between the runs of one method (what a sweep varied)."""
    return [c for c in group.columns if c.startswith("param.") and group[c].nunique(dropna=True) > 1]


def draw_volume_time_vs_error(ax, runs, scene):
    """Each run of the volume view as a point (frame time, error), labelled with the parameters its method's
    runs vary, each method's Pareto front as a step line, the constant baseline dashed; log axes."""
    for label, group in runs.groupby("label"):
        x = group["frame_ms"].to_numpy(float)
        y = group["volume_error"].to_numpy(float)
        floor = 0.5 * float(y[y > 0].min()) if (y > 0).any() else 1e-6
        drawn = np.maximum(y, floor)
        points = ax.scatter(x, drawn, alpha=0.6, s=22)
        front = pareto_front(list(zip(x, y)))
        ax.step(x[front], drawn[front], where="post", color=points.get_facecolor()[0], label=f"{label} (Pareto front)",
                linewidth=1.5)
        varying = _varying_params(group)
        names = [c[len("param."):] for c in varying]
        # A prefix every varied name shares (volume_step, volume_refine: "volume_") is dropped from the labels.
        prefix = os.path.commonprefix(names) if len(names) > 1 else ""
        prefix = prefix[:prefix.rfind("_") + 1]
        for xi, yi, (_, row) in zip(x, drawn, group.iterrows()):
            text = ", ".join(f"{n[len(prefix):]} {row[c]}" for n, c in zip(names, varying))
            if text:
                ax.annotate(text, (xi, yi), fontsize=5, xytext=(3, 2), textcoords="offset points", alpha=0.8)
    baseline = runs["volume_baseline"].dropna()
    if len(baseline):
        ax.axhline(float(baseline.median()), color="k", linestyle="--", linewidth=1.2, label="constant baseline")
    net = bool(runs["volume_error_is_net"].any())
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frame time, median [ms] (log)")
    ax.set_ylabel(f"camera_volume {'net error' if net else 'nrmse'} (log)")
    ax.set_title(f"{scene}: volume view, frame time vs error (lines: Pareto fronts)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)


def volume_time_vs_error(runs, scene, directory):
    """The volume view's time-vs-error figure written to disk (paths)."""
    fig, ax = plt.subplots(figsize=(7.2, 5.0))
    draw_volume_time_vs_error(ax, runs, scene)
    return _save(fig, directory, f"volume_time_vs_error_{scene}")


def volume_section(frame, scene, fig_dir, tab_dir, sweep_dir):
    """Markdown lines for the scene's volume view; empty where no run measured one."""
    runs = volume_runs(frame, scene)
    if runs.empty:
        return []
    table = volume_table(runs, scene)
    path = os.path.join(tab_dir, f"volume_{scene}.md")
    with open(path + ".tmp", "w") as f:
        f.write(table + "\n")
    os.replace(path + ".tmp", path)
    out = ["### Volume caustics (camera_volume)", ""]
    plot = volume_time_vs_error(runs, scene, fig_dir)
    out += [f"![{os.path.basename(plot[0])}](figures/{os.path.basename(plot[0])})", "",
            f"Figure: {scene}, the volume view (camera_volume), each point one run, labelled with the parameters "
            "its method's runs vary. Error axis: net error against the reference's single-scattering view (raw "
            "nrmse where no net error was recorded; 0 drawn at half the smallest positive value). Lines: Pareto "
            "fronts. Dashed line: the constant baseline.", ""]
    paths = volume_images(runs, scene, fig_dir, sweep_dir)
    if paths:
        out += [f"![{os.path.basename(paths[0])}](figures/{os.path.basename(paths[0])})", ""]
    return out + [table, ""]
