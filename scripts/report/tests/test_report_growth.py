"""The growth of frame time with grid: series, fitted log-log slopes, the growth table and its place in the
report, on synthetic sweeps whose times follow known power laws."""
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import pandas as pd

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
sys.path.insert(0, HERE)

from test_report import write_sweep  # noqa: E402

GRIDS = (32, 64, 128, 256, 512)


def surface_ms(grid):
    return 1e-4 * grid ** 2            # exactly grid^2


def volume_ms(grid):
    return 5.0 + 1e-5 * grid ** 3      # a fixed 5 ms (lookups) plus grid^3


def growth_sweep_rows():
    rows = []

    def add(method, grid, ms, status="ok", **params):
        run_id = f"pool-f30-{method}-grid={grid}" + "".join(f"-{k}={v}" for k, v in params.items())
        rows.append(dict({"run_id": run_id, "scene": "pool", "frame": 30, "method": method, "param.grid": grid,
                          "param.map": params.get("map", ""), "grid": grid, "iterations": 1,
                          "time_ms_median": ms, "frame_ms_median": ms, "frame_time": "update+render",
                          "nrmse": 0.1, "nrmse_fit": 0.1, "error_net": 0.1, "noise_nrmse": 0.01,
                          "radiometric": "true", "status": status, "message": ""}))

    for grid in GRIDS:
        # Two settings of another parameter: each its own series; the map=768 one costs 3 ms more.
        add("surface", grid, surface_ms(grid), map=0)
        add("surface", grid, surface_ms(grid) + 3.0, map=768)
        add("volume", grid, volume_ms(grid))
    add("volume", 1024, 1e6, status="failed")   # not ok: neither fitted nor listed
    for grid in (64, 128):                      # two grids: drawn in the figure, not in the table
        add("short", grid, 0.01 * grid)
    return rows


def frame():
    from load import add_derived_columns

    return add_derived_columns(pd.DataFrame(growth_sweep_rows()).replace("", np.nan))


def slope_by_hand(grids, times):
    """cov(log g, log t) / var(log g), written out: an implementation independent of growth.loglog_slope."""
    x, y = np.log(np.asarray(grids, float)), np.log(np.asarray(times, float))
    return float(((x - x.mean()) * (y - y.mean())).sum() / ((x - x.mean()) ** 2).sum())


class GrowthFitTest(unittest.TestCase):
    def test_series_split_by_the_other_varied_parameter(self):
        from growth import grid_series

        series = {label: times for label, _, times in grid_series(frame(), "pool")}
        self.assertEqual(sorted(series), ["short", "surface map=0", "surface map=768", "volume"])
        self.assertEqual(list(series["volume"].index), list(GRIDS))   # the failed run at 1024 is left out
        self.assertAlmostEqual(series["surface map=768"][128], surface_ms(128) + 3.0)

    def test_slopes_of_known_power_laws(self):
        from growth import growth_rows

        rows = {r["series"]: r for r in growth_rows(frame(), "pool")}
        self.assertNotIn("short", rows)   # 2 grids: below the table's minimum of 3
        self.assertAlmostEqual(rows["surface map=0"]["slope"], 2.0, places=9)
        self.assertAlmostEqual(rows["surface map=0"]["slope_upper"], 2.0, places=9)
        volume = rows["volume"]
        self.assertEqual(volume["upper_grids"], [128, 256, 512])
        self.assertAlmostEqual(volume["slope"], slope_by_hand(GRIDS, [volume_ms(g) for g in GRIDS]), places=9)
        self.assertAlmostEqual(volume["slope_upper"],
                               slope_by_hand(GRIDS[2:], [volume_ms(g) for g in GRIDS[2:]]), places=9)
        # The fixed 5 ms flattens the small grids: the upper half comes nearer the cells' exponent 3.
        self.assertLess(volume["slope"], volume["slope_upper"])
        self.assertLess(volume["slope_upper"], 3.0)
        self.assertGreater(volume["slope_upper"], 2.5)
        self.assertEqual((volume["ms_first"], volume["ms_last"]), (volume_ms(32), volume_ms(512)))


class GrowthReportTest(unittest.TestCase):
    def test_table_files_and_report_section(self):
        with tempfile.TemporaryDirectory() as d:
            write_sweep(d, growth_sweep_rows(), {})
            result = subprocess.run([sys.executable, os.path.join(os.path.dirname(HERE), "report.py"), d],
                                    capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(os.path.join(d, "tables", "growth_pool.md")) as f:
                md = f.read()
            self.assertIn("| method | grids | ms at first grid | ms at last grid | slope, all grids | "
                          "slope, upper half |", md)
            self.assertIn("| surface map=0 | 32 64 128 256 512 | 0.102 | 26.2 | 2.00 | 2.00 (128-512) |", md)
            self.assertNotIn("| short |", md)
            with open(os.path.join(d, "tables", "growth_pool.tex")) as f:
                tex = f.read()
            self.assertIn("surface map=0 & 32 64 128 256 512", tex)
            self.assertIn("\\label{tab:growth-pool}", tex)
            with open(os.path.join(d, "report.md")) as f:
                report = f.read()
            self.assertIn(md.strip(), report)
            for ext in ("png", "pdf"):
                self.assertTrue(os.path.getsize(os.path.join(d, "figures", f"fps_vs_grid_pool.{ext}")) > 1000)

    def test_figure_legend_quotes_the_tables_slope(self):
        import matplotlib.pyplot as plt

        import figures

        captured = []
        save = figures._save
        figures._save = lambda fig, directory, name: captured.append(fig) or [name]
        try:
            figures.fps_vs_grid(frame(), "pool", "unused")
        finally:
            figures._save = save
        ax = captured[0].axes[0]
        labels = [line.get_label() for line in ax.get_lines()]
        self.assertIn("surface map=0: time ~ grid^2.00", labels)
        self.assertIn("short: time ~ grid^1.00", labels)   # 2 grids still draw a line
        volume = [line for line in ax.get_lines() if line.get_label().startswith("volume")][0]
        self.assertTrue(np.allclose(volume.get_ydata(), [1000.0 / volume_ms(g) for g in GRIDS]))
        plt.close(captured[0])


if __name__ == "__main__":
    unittest.main()
