"""Reading a sweep directory: results.csv, manifest.json and per-run images."""
import json
import os
import sys

import numpy as np
import pandas as pd

# Boolean columns of results.csv (issue 11). Skipped and failed runs leave them empty, older sweeps lack
# them: both read as false so counts and flags never invent a condition.
FLAGS = ("noisy_timing", "no_better_than_flat", "below_reference_noise", "consistent_with_reference",
         "noise_target_met")


def _truthy(series):
    return series.astype(str).str.strip().str.lower().isin(["true", "1"])


def same_setting(series, value):
    """Where a run's parameter column holds `value` (JSON's false and the CSV's "false" alike: compared as
    lower-case text)."""
    return series.astype(str).str.strip().str.lower() == str(value).strip().lower()


def with_settings(runs, settings):
    """The runs whose parameter columns hold every one of `settings` (a dict; a key without a column picks
    nothing out)."""
    for key, value in (settings or {}).items():
        column = f"param.{key}"
        if column in runs:
            runs = runs[same_setting(runs[column], value)]
    return runs


def numeric(frame, column):
    """The column as numbers (NaN where empty or not a number; all NaN where the column is absent)."""
    if column not in frame:
        return pd.Series(np.nan, index=frame.index)
    return pd.to_numeric(frame[column], errors="coerce")


def add_derived_columns(frame):
    """The columns every figure and table reads, whatever the sweep's age.

    error          net error (reference noise removed) of the method's kind where the sweep wrote one,
                   else the raw nrmse (radiometric) or scale-fitted nrmse (otherwise): old sweeps still report
    error_lo/hi    its 95 % interval (NaN where only the raw error exists)
    error_raw      the raw error of the same kind, kept beside the net one
    error_is_net   which of the two `error` holds, so captions can say so
    frame_ms       per-frame cost (update + render for animated scenes), else the render time
    frame_fps      1000 / frame_ms: the fps every plot and table quotes, consistent with frame_ms
    """
    frame["radiometric"] = _truthy(frame["radiometric"])
    for flag in FLAGS:
        frame[flag] = _truthy(frame[flag]) if flag in frame else False
    # docs/design.md section 6: nrmse for radiometric methods, the scale-fitted nrmse otherwise (labelled "fit").
    frame["error_raw"] = np.where(frame["radiometric"], numeric(frame, "nrmse"), numeric(frame, "nrmse_fit"))
    net = numeric(frame, "error_net")
    frame["error_is_net"] = np.isfinite(net)
    frame["error"] = np.where(frame["error_is_net"], net, frame["error_raw"])
    frame["error_lo"] = np.where(frame["error_is_net"], numeric(frame, "error_net_lo"), np.nan)
    frame["error_hi"] = np.where(frame["error_is_net"], numeric(frame, "error_net_hi"), np.nan)
    for column in ("baseline_error", "noise_nrmse", "noise_target"):
        frame[column] = numeric(frame, column)
    per_frame = numeric(frame, "frame_ms_median")
    render = numeric(frame, "time_ms_median")
    frame["frame_ms"] = np.where(np.isfinite(per_frame), per_frame, render)
    with np.errstate(divide="ignore"):
        frame["frame_fps"] = 1000.0 / frame["frame_ms"]
    frame["label"] = np.where(frame["radiometric"], frame["method"], frame["method"] + " (fit)")
    return frame


def read_results(directory):
    path = os.path.join(directory, "results.csv")
    if not os.path.exists(path):
        sys.exit(f"report: {path}: missing; run `caustics sweep` first")
    frame = pd.read_csv(path)
    required = {"run_id", "scene", "method", "status", "time_ms_median", "nrmse", "radiometric"}
    missing = required - set(frame.columns)
    if missing:
        sys.exit(f"report: {path}: missing columns {sorted(missing)}")
    return add_derived_columns(frame)


def read_manifest(directory):
    path = os.path.join(directory, "manifest.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


def machine_parts(manifest):
    """The machine states a sweep recorded (manifest.json "machine", then each resumed part's), dicts only."""
    parts = [manifest.get("machine")] + [r.get("machine") for r in manifest.get("resumed", [])]
    return [p for p in parts if isinstance(p, dict)]


def read_image(path):
    """Single-channel float image as a 2-D numpy array, or None if the file is missing."""
    if not os.path.exists(path):
        return None
    import OpenImageIO as oiio  # Debian: python3-openimageio

    image = oiio.ImageInput.open(path)
    if image is None:
        return None
    pixels = image.read_image("float")
    image.close()
    pixels = np.asarray(pixels, dtype=np.float64)
    return pixels[:, :, 0] if pixels.ndim == 3 else pixels


def run_images(sweep_dir, picks, name, shape):
    """(run, image) for each picked run whose DIR/runs/<run_id>/<name> exists with the truth's shape."""
    maps = [(p, read_image(os.path.join(sweep_dir, "runs", p["run_id"], name))) for p in picks]
    return [(p, m) for p, m in maps if m is not None and m.shape == shape]


def ok_runs(frame):
    """Runs with a finite error and frame time: what plots and tables use."""
    ok = frame[(frame["status"] == "ok") & np.isfinite(frame["error"]) & np.isfinite(frame["frame_ms"])]
    return ok.copy()


def scene_baseline(frame, scene):
    """The no-caustic baseline's net error on a scene: one value per scene/frame, the median over its rows."""
    values = frame.loc[frame["scene"] == scene, "baseline_error"].dropna()
    return float(values.median()) if not values.empty else None
