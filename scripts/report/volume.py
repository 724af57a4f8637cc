"""The third view, volume caustic radiance L_v (camera_volume): a table and an image row per scene whose
medium scatters. The receiver-map tables and figures of report.py are unchanged; these sit beside them."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from figures import _save, bare_axes  # noqa: E402
from load import numeric, read_image, run_images  # noqa: E402


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
    paths = volume_images(runs, scene, fig_dir, sweep_dir)
    if paths:
        out += [f"![{os.path.basename(paths[0])}](figures/{os.path.basename(paths[0])})", ""]
    return out + [table, ""]
