"""Paper-style figures of a sweep: time vs error, error vs iterations, fps vs grid, image grids."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize  # noqa: E402

from load import ok_runs, read_image  # noqa: E402
from pareto import pareto_front  # noqa: E402

MARKERS = "osD^v<>ph*"


# A caustic whose peak exceeds this many times the reference's 99.5th percentile is shown on a log scale:
# a linear scale clipped at the percentile saturates the focus (the sphere's spot).
CONCENTRATED_PEAK_RATIO = 4.0
LOG_DECADES = 3.0


def irradiance_cmap():
    """inferno, with zero (masked by a log scale) drawn as the scale's darkest colour."""
    cmap = plt.get_cmap("inferno").copy()
    cmap.set_bad(cmap(0.0))
    return cmap


def irradiance_norm(reference):
    """Colour scale of the receiver maps and its label: linear up to the 99.5th percentile, or, for a
    concentrated caustic, logarithmic over LOG_DECADES decades below the peak so the focus is not clipped."""
    finite = reference[np.isfinite(reference)]
    peak = float(finite.max()) if finite.size else 0.0
    scale = float(np.percentile(finite, 99.5)) if finite.size else 0.0
    if peak > 0.0 and peak > CONCENTRATED_PEAK_RATIO * scale:
        return LogNorm(vmin=peak * 10.0 ** -LOG_DECADES, vmax=peak, clip=True), "E_c [W/m^2], log scale"
    return Normalize(vmin=0.0, vmax=scale or 1.0, clip=True), "E_c [W/m^2]"


def _save(fig, directory, name):
    paths = []
    for ext in ("png", "pdf"):
        path = os.path.join(directory, f"{name}.{ext}")
        tmp = path + ".tmp." + ext
        fig.savefig(tmp, dpi=150, bbox_inches="tight")
        os.replace(tmp, path)
        paths.append(path)
    plt.close(fig)
    return paths


def _style(method_labels):
    cmap = plt.get_cmap("tab10")
    return {label: (cmap(i % 10), MARKERS[i % len(MARKERS)]) for i, label in enumerate(sorted(method_labels))}


def time_vs_error(frame, scene, directory):
    """Every run as a point, each method's Pareto front, log axes, the reference noise floor as a band."""
    runs = ok_runs(frame[frame["scene"] == scene])
    if runs.empty:
        return None
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    style = _style(runs["label"].unique())
    for label, group in runs.groupby("label"):
        color, marker = style[label]
        points = list(zip(group["time_ms_median"], group["error"]))
        ax.scatter(group["time_ms_median"], group["error"], color=color, marker=marker, alpha=0.45, s=22)
        front = [points[i] for i in pareto_front(points)]
        ax.step([p[0] for p in front], [p[1] for p in front], where="post", color=color, marker=marker,
                label=label, linewidth=1.6)
    noise = runs["noise_nrmse"].dropna() if "noise_nrmse" in runs else []
    if len(noise):
        lo, hi = float(np.min(noise)), float(np.max(noise))
        ax.axhspan(lo, 3.0 * hi, color="0.6", alpha=0.25, label="reference noise (1x-3x)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frame time, median [ms]  (log)")
    ax.set_ylabel("receiver-map nrmse vs reference  (log)")
    ax.set_title(f"{scene}: time vs error (lines: Pareto fronts)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, directory, f"time_vs_error_{scene}")


def error_vs_iterations(frame, scene, directory):
    runs = ok_runs(frame[frame["scene"] == scene])
    runs = runs[np.isfinite(runs.get("iterations", np.nan))] if "iterations" in runs else runs.iloc[0:0]
    if runs.empty:
        return None
    # Only (method, grid) pairs that were run at several iteration counts make a line.
    lines = [(key, g) for key, g in runs.groupby(["label", "grid"]) if g["iterations"].nunique() >= 2]
    if not lines:
        return None
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    style = _style(runs["label"].unique())
    grids = sorted({grid for (_, grid), _ in lines})
    dashes = ["-", "--", ":", "-."]
    for (label, grid), group in lines:
        g = group.groupby("iterations")["error"].median().sort_index()
        color, marker = style[label]
        ax.plot(g.index, g.values, color=color, marker=marker, label=f"{label}, grid {int(grid)}",
                linestyle=dashes[grids.index(grid) % len(dashes)])
    ax.set_yscale("log")
    ax.set_xlabel("iterations")
    ax.set_ylabel("receiver-map nrmse vs reference  (log)")
    ax.set_title(f"{scene}: error vs iterations")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, directory, f"error_vs_iterations_{scene}")


def fps_vs_grid(frame, scene, directory):
    """fps against grid on log-log axes; the legend gives the fitted slope d log fps / d log grid."""
    runs = ok_runs(frame[frame["scene"] == scene])
    if runs.empty or runs["grid"].nunique() < 2:
        return None
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    style = _style(runs["method"].unique())   # speed is not fitted: plain method names
    for label, group in runs.groupby("method"):
        g = group.groupby("grid")["fps"].median().sort_index()
        if len(g) < 2:
            continue
        slope = np.polyfit(np.log(g.index.values.astype(float)), np.log(g.values), 1)[0]
        color, marker = style[label]
        ax.plot(g.index, g.values, color=color, marker=marker, label=f"{label} (slope {slope:+.2f})")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("grid resolution  (log2)")
    ax.set_ylabel("frames per second of render()  (log)")
    ax.set_title(f"{scene}: fps vs grid (fitted log-log slope)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, directory, f"fps_vs_grid_{scene}")


def _chosen_runs(runs, chosen):
    """One run per method: the configuration the spec names, else the lowest-error run."""
    picks = []
    for method, group in runs.groupby("method"):
        pick = group
        for key, value in (chosen.get(method) or {}).items():
            column = f"param.{key}"
            if column in pick:
                pick = pick[pick[column].astype(str) == str(value)]
        pick = pick if not pick.empty else group
        picks.append(pick.sort_values("error").iloc[0])
    return picks


def image_grid(frame, scene, directory, sweep_dir, chosen):
    """Reference | each method | signed difference (one shared, labelled colour bar), like Shah Fig. 6-7."""
    runs = ok_runs(frame[frame["scene"] == scene])
    if runs.empty:
        return None
    picks = _chosen_runs(runs, chosen)
    frame_no = int(picks[0]["frame"])
    reference = read_image(os.path.join(sweep_dir, "references", f"{scene}-f{frame_no}", "reference_receiver.exr"))
    if reference is None:
        return None
    maps = [(p, read_image(os.path.join(sweep_dir, "runs", p["run_id"], "receiver.exr"))) for p in picks]
    maps = [(p, m) for p, m in maps if m is not None and m.shape == reference.shape]
    if not maps:
        return None
    norm, irradiance_label = irradiance_norm(reference)
    diffs = []
    for p, m in maps:
        fit = 1.0 if p["radiometric"] else float(p.get("fit_scale", 1.0))
        diffs.append(m * fit - reference)
    limit = max(float(np.percentile(np.abs(d), 99.5)) for d in diffs) or 1.0
    n = len(maps)
    beauty = [os.path.join(sweep_dir, "runs", p["run_id"], "beauty.png") for p, _ in maps]
    rows = 3 if any(os.path.exists(b) for b in beauty) else 2
    fig, axes = plt.subplots(rows, n + 1, figsize=(2.6 * (n + 1) + 0.8, 2.8 * rows), squeeze=False)
    im = axes[0][0].imshow(reference, cmap=irradiance_cmap(), norm=norm, origin="lower")
    axes[0][0].set_title("reference", fontsize=9)
    for i, (p, m) in enumerate(maps, start=1):
        fit = 1.0 if p["radiometric"] else float(p.get("fit_scale", 1.0))
        axes[0][i].imshow(m * fit, cmap=irradiance_cmap(), norm=norm, origin="lower")
        title = p["label"] + f"\ngrid {int(p['grid'])}, {p['time_ms_median']:.2f} ms"
        axes[0][i].set_title(title, fontsize=8)
        dm = axes[1][i].imshow(diffs[i - 1], cmap="RdBu_r", vmin=-limit, vmax=limit, origin="lower")
        axes[1][i].set_title(f"{'fit x ' if not p['radiometric'] else ''}method - reference\n"
                             f"nrmse {p['error']:.3f}", fontsize=8)
        if rows == 3 and os.path.exists(beauty[i - 1]):
            axes[2][i].imshow(plt.imread(beauty[i - 1]))
            axes[2][i].set_title("beauty (camera)", fontsize=8)
    stderr = read_image(os.path.join(sweep_dir, "references", f"{scene}-f{frame_no}", "reference_stderr.exr"))
    if stderr is not None and stderr.shape == reference.shape:
        axes[1][0].imshow(stderr, cmap="RdBu_r", vmin=-limit, vmax=limit, origin="lower")
        axes[1][0].set_title("reference std. error", fontsize=8)
    for row in axes:
        for a in row:
            a.set_xticks([])
            a.set_yticks([])
            if not a.images:
                a.axis("off")
    fig.colorbar(im, ax=list(axes[0]), shrink=0.8, label=irradiance_label)
    fig.colorbar(dm, ax=list(axes[1]), shrink=0.8, label="signed difference [W/m^2]")
    fig.suptitle(f"{scene}, frame {frame_no}: receiver maps", fontsize=10)
    return _save(fig, directory, f"images_{scene}")
