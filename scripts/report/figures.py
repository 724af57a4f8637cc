"""Paper-style figures of a sweep: time vs error, error vs iterations, fps vs grid, image grids."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.container import ErrorbarContainer  # noqa: E402
from matplotlib.colors import LogNorm, Normalize  # noqa: E402
from matplotlib.ticker import LogFormatter  # noqa: E402

from growth import grid_series, loglog_slope  # noqa: E402
from load import numeric, ok_runs, read_image, run_images, scene_baseline, with_settings  # noqa: E402
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


class PlainLogFormatter(LogFormatter):
    """Log-axis labels as plain numbers ("2", "0.5"): a sweep spanning less than a decade otherwise gets
    "2 x 10^0" or, narrower still, repeated rounded labels ("9e-01, 9e-01")."""

    def _num_to_string(self, x, vmin, vmax):
        return f"{x:.3g}"


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


def bare_axes(axes):
    """Image panes: no ticks; panes left without an image are hidden."""
    for row in axes:
        for a in row:
            a.set_xticks([])
            a.set_yticks([])
            if not a.images:
                a.axis("off")


def _style(method_labels):
    cmap = plt.get_cmap("tab10")
    return {label: (cmap(i % 10), MARKERS[i % len(MARKERS)]) for i, label in enumerate(sorted(method_labels))}


# Caption phrases the report and the figures share, so the two never describe the axes differently.
NET_ERROR = "net error (reference noise removed), 95 % interval"
FRAME_TIME = "frame time = update + render for animated scenes"
BASELINE_LABEL = "no-caustic baseline (flat interface)"


def log_floor(values):
    """Where a log axis draws a net error of 0: half the smallest positive value. Such a run cannot be told
    from the truth at this reference noise; dropping it (what a log axis does to 0) would hide the best runs."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values) & (values > 0)]
    return 0.5 * float(values.min()) if values.size else 1e-6


def has_frame_time(frame):
    return bool(numeric(frame, "frame_ms_median").notna().any())


def draw_time_vs_error(ax, frame, scene):
    """Every run as a point with its net error's 95 % interval as a vertical bar, each method's Pareto front,
    the no-caustic baseline as a horizontal line and the reference noise as a band, on log axes.

    Returns what a caption needs (floor, number of runs drawn at it, baseline, ...) or None without runs."""
    runs = ok_runs(frame[frame["scene"] == scene])
    if runs.empty:
        return None
    baseline = scene_baseline(frame, scene)
    floor = log_floor(np.concatenate([runs[c].to_numpy(float) for c in ("error", "error_lo", "error_hi")]
                                     + [[baseline if baseline is not None else np.nan]]))
    style = _style(runs["label"].unique())
    clipped_total = bars_clipped = 0
    for label, group in runs.groupby("label"):
        color, marker = style[label]
        x = group["frame_ms"].to_numpy(float)
        error = group["error"].to_numpy(float)
        y = np.maximum(error, floor)
        lo = np.maximum(np.where(np.isfinite(group["error_lo"]), group["error_lo"], y), floor)
        hi = np.maximum(np.where(np.isfinite(group["error_hi"]), group["error_hi"], y), floor)
        ax.errorbar(x, y, yerr=[np.maximum(y - lo, 0.0), np.maximum(hi - y, 0.0)], fmt="none", ecolor=color,
                    alpha=0.5, elinewidth=0.9, capsize=2)
        ax.scatter(x, y, color=color, marker=marker, alpha=0.45, s=22)
        clipped = error <= 0.0
        bars_clipped += int((np.nan_to_num(group["error_lo"].to_numpy(float), nan=1.0) <= 0.0).sum())
        if clipped.any():
            ax.scatter(x[clipped], y[clipped], facecolors="none", edgecolors="k", marker="o", s=90,
                       linewidths=1.0, label=None if clipped_total else f"net error 0, drawn at {floor:.2g}")
            clipped_total += int(clipped.sum())
        # The front ranks the true values (0 beats any positive error); only the drawing is clipped.
        front = pareto_front(list(zip(x, error)))
        ax.step(x[front], y[front], where="post", color=color, marker=marker, label=label, linewidth=1.6)
    if baseline is not None:
        ax.axhline(max(baseline, floor), color="k", linestyle="--", linewidth=1.2, label=BASELINE_LABEL)
    noise = runs["noise_nrmse"].dropna()
    noise = noise[noise > 0]
    if len(noise):
        ax.axhspan(float(noise.min()), 3.0 * float(noise.max()), color="0.6", alpha=0.25,
                   label="reference noise (1x-3x)")
    has_net = bool(runs["error_is_net"].any())
    has_frame = has_frame_time(runs)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(f"{FRAME_TIME}\n(median ms, log)" if has_frame else "render time, median [ms]  (log)")
    ax.xaxis.set_major_formatter(PlainLogFormatter())
    ax.xaxis.set_minor_formatter(PlainLogFormatter(minor_thresholds=(2, 0.5)))
    ax.set_ylabel(f"{NET_ERROR}\n(receiver map, log)" if has_net else "receiver-map nrmse vs reference  (log)")
    ax.set_title(f"{scene}: frame time vs {'net ' if has_net else ''}error (lines: Pareto fronts)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return {"floor": floor, "clipped": clipped_total, "bars_clipped": bars_clipped, "baseline": baseline,
            "has_net": has_net, "has_frame_time": has_frame, "raw_only": int((~runs["error_is_net"]).sum()),
            "noise": float(noise.max()) if len(noise) else 0.0}


def error_bar_extents(ax):
    """(x, lower end, upper end) of every vertical error bar drawn on ax: what tests inspect."""
    extents = []
    for container in ax.containers:
        if isinstance(container, ErrorbarContainer) and container.has_yerr:
            for collection in container.lines[2]:
                for segment in collection.get_segments():
                    if len(segment) == 0:  # a run without a bar (NaN) leaves an empty segment
                        continue
                    extents.append((float(segment[0][0]), float(min(segment[:, 1])), float(max(segment[:, 1]))))
    return extents


def time_vs_error_caption(scene, info):
    """The report.md caption of draw_time_vs_error's figure."""
    if info["has_net"]:
        text = (f"Figure: {scene}, each point one run. Error axis: {NET_ERROR} drawn as vertical bars. ")
    else:
        text = f"Figure: {scene}, each point one run. Error axis: raw nrmse (this sweep has no net error). "
    if info["raw_only"] and info["has_net"]:
        text += f"{info['raw_only']} run(s) without a net error show their raw error, without bars. "
    text += (f"Time axis: {FRAME_TIME}, median ms. " if info["has_frame_time"]
             else "Time axis: render time, median ms (this sweep records no per-frame cost). ")
    text += "Lines: Pareto fronts; methods marked (fit) are measured after a least-squares scale fit. "
    if info["baseline"] is not None:
        text += f"Dashed line: {BASELINE_LABEL}, net error {info['baseline']:.3g}. "
    if info["noise"] > 0:
        text += "Grey band: 1x-3x the reference noise. "
    if info["clipped"] or info["bars_clipped"]:
        text += (f"A log axis has no 0: {info['clipped']} run(s) with net error 0 (circled) and "
                 f"{info['bars_clipped']} interval(s) reaching 0 are drawn down to {info['floor']:.2g}, half the "
                 f"smallest positive value. ")
    return text.strip()


def time_vs_error(frame, scene, directory):
    """The time-vs-error figure written to disk: (paths, report.md caption), or None without runs."""
    fig, ax = plt.subplots(figsize=(7.2, 5.0))
    info = draw_time_vs_error(ax, frame, scene)
    if info is None:
        plt.close(fig)
        return None
    return _save(fig, directory, f"time_vs_error_{scene}"), time_vs_error_caption(scene, info)


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
    floor = log_floor(runs["error"])
    for (label, grid), group in lines:
        g = group.groupby("iterations")["error"].median().sort_index()
        color, marker = style[label]
        ax.plot(g.index, np.maximum(g.values, floor), color=color, marker=marker,
                label=f"{label}, grid {int(grid)}", linestyle=dashes[grids.index(grid) % len(dashes)])
    ax.set_yscale("log")
    ax.set_xlabel("iterations")
    net = bool(runs["error_is_net"].any())
    ax.set_ylabel("net error (reference noise removed), median  (log)" if net
                  else "receiver-map nrmse vs reference  (log)")
    zero = " (0 drawn at %.2g)" % floor if (runs["error"] <= 0).any() else ""
    ax.set_title(f"{scene}: error vs iterations{zero}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, directory, f"error_vs_iterations_{scene}")


def fps_vs_grid(frame, scene, directory):
    """fps (1000 / frame time, render only in older sweeps) against grid on log-log axes, one line per
    method and setting of its other varied parameters (growth.grid_series); the legend gives the fitted
    exponent s of frame time ~ grid^s (the fps line's slope is -s), the growth table's "all grids" column."""
    series = [s for s in grid_series(frame, scene) if len(s[2]) >= 2]
    if not series:
        return None
    runs = ok_runs(frame[frame["scene"] == scene])
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    style = _style(sorted({method for _, method, _ in series}))   # speed is not fitted: plain method names
    dashes = ["-", "--", ":", "-."]
    seen = {}
    for label, method, times in series:
        color, marker = style[method]
        slope = loglog_slope(times.index, times.values)
        ax.plot(times.index, 1000.0 / times.values, color=color, marker=marker,
                linestyle=dashes[seen.setdefault(method, 0) % len(dashes)], label=f"{label}: time ~ grid^{slope:.2f}")
        seen[method] += 1
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("grid resolution  (log2)")
    ax.set_ylabel("fps = 1000 / frame time  (log)" if has_frame_time(runs)
                  else "frames per second of render()  (log)")
    ax.set_title(f"{scene}: fps vs grid (fitted exponent of frame time)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, directory, f"fps_vs_grid_{scene}")


def _chosen_runs(runs, chosen):
    """One run per method: the configuration the spec names, else the lowest-error run."""
    picks = []
    for method, group in runs.groupby("method"):
        pick = with_settings(group, chosen.get(method))
        pick = pick if not pick.empty else group
        picks.append(pick.sort_values("error").iloc[0])
    return picks


def chosen_receiver_maps(frame, scene, sweep_dir, chosen):
    """The receiver truth of a scene and each method's chosen run against it (None where the sweep has no
    truth map or no run map): a dict with `truth`, `truth_title`, `ref_dir`, `frame_no`, `maps` ((run, map)
    pairs, maps scaled by the run's fit where it is not radiometric), `diffs` (map - truth) and `limit` (the
    99.5th percentile of |diff| over all runs, the shared scale of the differences)."""
    runs = ok_runs(frame[frame["scene"] == scene])
    if runs.empty:
        return None
    picks = _chosen_runs(runs, chosen)
    frame_no = int(picks[0]["frame"])
    ref_dir = os.path.join(sweep_dir, "references", f"{scene}-f{frame_no}")
    # The receiver truth the errors were measured against: the analytic closed form where the sweep wrote
    # one (zero noise), else the Monte Carlo reference.
    truth = read_image(os.path.join(ref_dir, "truth_receiver.exr"))
    truth_title = "analytic truth"
    if truth is None:
        truth = read_image(os.path.join(ref_dir, "reference_receiver.exr"))
        truth_title = "reference"
    if truth is None:
        return None
    maps = run_images(sweep_dir, picks, "receiver.exr", truth.shape)
    if not maps:
        return None
    maps = [(p, m * (1.0 if p["radiometric"] else float(p.get("fit_scale", 1.0)))) for p, m in maps]
    diffs = [m - truth for _, m in maps]
    limit = max(float(np.percentile(np.abs(d), 99.5)) for d in diffs) or 1.0
    return {"truth": truth, "truth_title": truth_title, "ref_dir": ref_dir, "frame_no": frame_no, "maps": maps,
            "diffs": diffs, "limit": limit}


def image_grid(frame, scene, directory, sweep_dir, chosen):
    """Reference | each method | signed difference (one shared, labelled colour bar), like Shah Fig. 6-7."""
    c = chosen_receiver_maps(frame, scene, sweep_dir, chosen)
    if c is None:
        return None
    reference, truth_title, ref_dir, frame_no = c["truth"], c["truth_title"], c["ref_dir"], c["frame_no"]
    maps, diffs, limit = c["maps"], c["diffs"], c["limit"]
    norm, irradiance_label = irradiance_norm(reference)
    n = len(maps)
    beauty = [os.path.join(sweep_dir, "runs", p["run_id"], "beauty.png") for p, _ in maps]
    rows = 3 if any(os.path.exists(b) for b in beauty) else 2
    fig, axes = plt.subplots(rows, n + 1, figsize=(2.6 * (n + 1) + 0.8, 2.8 * rows), squeeze=False)
    im = axes[0][0].imshow(reference, cmap=irradiance_cmap(), norm=norm, origin="lower")
    axes[0][0].set_title(truth_title, fontsize=9)
    for i, (p, m) in enumerate(maps, start=1):
        axes[0][i].imshow(m, cmap=irradiance_cmap(), norm=norm, origin="lower")
        title = p["label"] + f"\ngrid {int(p['grid'])}, {p['frame_ms']:.2f} ms"
        axes[0][i].set_title(title, fontsize=8)
        dm = axes[1][i].imshow(diffs[i - 1], cmap="RdBu_r", vmin=-limit, vmax=limit, origin="lower")
        axes[1][i].set_title(f"{'fit x ' if not p['radiometric'] else ''}method - {truth_title}\n"
                             f"{'net error' if p['error_is_net'] else 'nrmse'} {p['error']:.3f}", fontsize=8)
        if rows == 3 and os.path.exists(beauty[i - 1]):
            axes[2][i].imshow(plt.imread(beauty[i - 1]))
            axes[2][i].set_title("beauty (camera)", fontsize=8)
    stderr = read_image(os.path.join(ref_dir, "reference_stderr.exr"))
    if truth_title == "reference" and stderr is not None and stderr.shape == reference.shape:
        axes[1][0].imshow(stderr, cmap="RdBu_r", vmin=-limit, vmax=limit, origin="lower")
        axes[1][0].set_title("reference std. error", fontsize=8)
    bare_axes(axes)
    fig.colorbar(im, ax=list(axes[0]), shrink=0.8, label=irradiance_label)
    fig.colorbar(dm, ax=list(axes[1]), shrink=0.8, label="signed difference [W/m^2]")
    fig.suptitle(f"{scene}, frame {frame_no}: receiver maps", fontsize=10)
    return _save(fig, directory, f"images_{scene}")
