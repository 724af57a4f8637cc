"""How a method's frame time grows with `grid`: the series the fps-vs-grid figure draws and the growth table
fits, so that both quote the same slope.

A series is one method with every other parameter held: where a sweep varies another parameter of the
method too (caustic_mapping's map or estimator, say), each combination is a series of its own, because a
median over different settings at one grid would fit neither of them.
"""
import numpy as np

from load import ok_runs

MIN_GRIDS_FOR_TABLE = 3   # two points always fit a line exactly: the table wants at least one to spare


def _value_text(value):
    if isinstance(value, float) and np.isfinite(value) and value.is_integer():
        return str(int(value))
    return str(value)


def grid_series(frame, scene):
    """[(label, method, per-grid median frame_ms as a pandas Series indexed by grid)] for a scene's ok runs,
    one per method and combination of its other varied parameters, sorted by label."""
    runs = ok_runs(frame[frame["scene"] == scene])
    runs = runs[np.isfinite(runs["grid"].astype(float))] if "grid" in runs else runs.iloc[0:0]
    series = []
    for method, group in runs.groupby("method"):
        params = [c for c in group.columns if c.startswith("param.") and c != "param.grid"]
        varied = [c for c in params if group[c].astype(str).nunique() > 1]
        setting = group[varied].astype(str).agg("|".join, axis=1) if varied else None
        parts = [part for _, part in group.groupby(setting)] if varied else [group]
        for part in parts:
            first = part.iloc[0]
            label = method + "".join(f" {c[len('param.'):]}={_value_text(first[c])}" for c in varied)
            times = part.groupby(part["grid"].astype(float))["frame_ms"].median().sort_index()
            series.append((label, method, times))
    return sorted(series, key=lambda s: s[0])


def loglog_slope(grids, times):
    """Least-squares slope of log(time) against log(grid): the exponent s of time ~ grid^s. NaN for fewer
    than two distinct grids."""
    grids = np.asarray(grids, dtype=float)
    times = np.asarray(times, dtype=float)
    if np.unique(grids).size < 2:
        return float("nan")
    return float(np.polyfit(np.log(grids), np.log(times), 1)[0])


def upper_half(times):
    """The points at or above the median grid, where fixed per-frame costs weigh least (for 5 grids the
    top 3, for 3 or 4 grids the top 2)."""
    grids = times.index.values.astype(float)
    return times[grids >= np.median(grids)]


def growth_rows(frame, scene):
    """One row per series with at least MIN_GRIDS_FOR_TABLE grids: numbers, not yet formatted."""
    rows = []
    for label, method, times in grid_series(frame, scene):
        if len(times) < MIN_GRIDS_FOR_TABLE:
            continue
        top = upper_half(times)
        rows.append({"series": label, "method": method, "grids": [int(g) for g in times.index],
                     "ms_first": float(times.iloc[0]), "ms_last": float(times.iloc[-1]),
                     "slope": loglog_slope(times.index, times.values),
                     "slope_upper": loglog_slope(top.index, top.values),
                     "upper_grids": [int(g) for g in top.index]})
    return rows
