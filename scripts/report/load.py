"""Reading a sweep directory: results.csv, manifest.json and per-run images."""
import json
import os
import sys

import numpy as np
import pandas as pd


def read_results(directory):
    path = os.path.join(directory, "results.csv")
    if not os.path.exists(path):
        sys.exit(f"report: {path}: missing; run `caustics sweep` first")
    frame = pd.read_csv(path)
    required = {"run_id", "scene", "method", "status", "time_ms_median", "nrmse", "radiometric"}
    missing = required - set(frame.columns)
    if missing:
        sys.exit(f"report: {path}: missing columns {sorted(missing)}")
    frame["radiometric"] = frame["radiometric"].astype(str).str.lower().isin(["true", "1"])
    # The error every figure plots: nrmse for radiometric methods, the scale-fitted nrmse otherwise
    # (DESIGN.md section 6; always labelled "fit").
    frame["error"] = np.where(frame["radiometric"], frame["nrmse"], frame.get("nrmse_fit", np.nan))
    frame["label"] = np.where(frame["radiometric"], frame["method"], frame["method"] + " (fit)")
    return frame


def read_manifest(directory):
    path = os.path.join(directory, "manifest.json")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return json.load(f)


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


def ok_runs(frame):
    """Runs with a finite error and timing: what plots and tables use."""
    ok = frame[(frame["status"] == "ok") & np.isfinite(frame["error"]) & np.isfinite(frame["time_ms_median"])]
    return ok.copy()
