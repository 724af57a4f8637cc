"""Report generation on a small synthetic sweep directory, and the Pareto front on hand-made points."""
import csv
import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

from pareto import pareto_front  # noqa: E402


def write_exr(path, pixels):
    import OpenImageIO as oiio

    os.makedirs(os.path.dirname(path), exist_ok=True)
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 1, "float")
    out = oiio.ImageOutput.create(path)
    out.open(path, spec)
    out.write_image(np.ascontiguousarray(pixels, dtype=np.float32)[:, :, None])  # 2-D arrays are misread
    out.close()


class ColourScaleTest(unittest.TestCase):
    def test_concentrated_caustic_gets_a_log_scale(self):
        from figures import irradiance_norm

        smooth = 1.0 + 0.5 * np.sin(np.linspace(0.0, 20.0, 64 * 64)).reshape(64, 64)
        norm, label = irradiance_norm(smooth)
        self.assertNotIn("log", label)
        self.assertAlmostEqual(norm.vmax, float(np.percentile(smooth, 99.5)))
        spot = np.full((64, 64), 1.0)
        spot[30:32, 30:32] = 300.0  # 4 of 4096 pixels: above the 99.5th percentile
        norm, label = irradiance_norm(spot)
        self.assertIn("log", label)
        self.assertEqual(norm.vmax, 300.0)
        self.assertAlmostEqual(norm.vmin, 0.3)


class ParetoTest(unittest.TestCase):
    def test_hand_made_front(self):
        points = [(1.0, 0.5), (2.0, 0.3), (2.5, 0.4), (3.0, 0.1), (0.5, 0.9), (3.0, 0.2), (4.0, 0.1), (2.0, 0.3)]
        # (2.5, 0.4) is beaten by (2.0, 0.3); (3.0, 0.2) by (3.0, 0.1); (4.0, 0.1) by (3.0, 0.1);
        # the second (2.0, 0.3) duplicates the first.
        self.assertEqual(pareto_front(points), [4, 0, 1, 3])

    def test_single_and_empty(self):
        self.assertEqual(pareto_front([]), [])
        self.assertEqual(pareto_front([(1.0, 1.0)]), [0])


class SameSettingTest(unittest.TestCase):
    # The paper settings of a spec (JSON values) pick runs by their CSV parameter columns, which pandas reads
    # as booleans, numbers or text: false matches False and "false", 128 matches 128.0 written as "128".
    def test_booleans_and_numbers(self):
        import pandas as pd
        from load import same_setting

        flags = pd.Series([True, False, "false", "TRUE", None])
        self.assertEqual(list(same_setting(flags, False)), [False, True, True, False, False])
        self.assertEqual(list(same_setting(flags, "true")), [True, False, False, True, False])
        grids = pd.Series(["128", "64", 128])
        self.assertEqual(list(same_setting(grids, 128)), [True, False, True])


class OldSweepReportTest(unittest.TestCase):
    """A sweep from before issue 11 (raw errors, render times only) must still report."""

    def test_every_figure_and_table(self):
        rng = np.random.default_rng(3)
        keep = os.environ.get("CAUSTICS_KEEP_REPORT")  # a folder to keep the output in, for looking at it
        with tempfile.TemporaryDirectory() as tmp:
            d = keep or tmp
            reference = 1.0 + 0.5 * np.sin(np.linspace(0, 6, 32))[None, :] * np.ones((32, 1))
            write_exr(os.path.join(d, "references", "sine-f0", "reference_receiver.exr"), reference)
            rows = []
            for method, radiometric in (("fast_method", True), ("relative_method", False)):
                for grid in (32, 64, 128):
                    for iterations in (1, 2, 3):
                        run_id = f"sine-f0-{method}-grid={grid}-iterations={iterations}"
                        error = 0.5 / grid ** 0.5 / iterations
                        image = reference * (1 + error * rng.standard_normal(reference.shape))
                        if not radiometric:
                            image = image * 0.25
                        write_exr(os.path.join(d, "runs", run_id, "receiver.exr"), image)
                        time = 0.01 * grid * iterations
                        rows.append({"run_id": run_id, "scene": "sine", "frame": 0, "method": method,
                                     "param.grid": grid, "param.iterations": iterations, "grid": grid,
                                     "iterations": iterations, "time_ms_median": time, "fps": 1000 / time,
                                     "nrmse": error if radiometric else 0.75, "nrmse_fit": error,
                                     "fit_scale": 1.0 if radiometric else 4.0, "noise_nrmse": 0.004,
                                     "radiometric": "true" if radiometric else "false",
                                     "status": "ok", "message": ""})
            rows.append(dict(rows[0], run_id="sine-f0-broken", status="failed", message="it broke"))
            with open(os.path.join(d, "results.csv"), "w", newline="") as f:
                writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
                writer.writeheader()
                writer.writerows(rows)
            with open(os.path.join(d, "manifest.json"), "w") as f:
                json.dump({"host": {"cpu": "test cpu", "cores": 2}, "threads": 2, "build_type": "Release",
                           "git_commit": "abc", "spec": {"report": {"paper_settings": {
                               "fast_method": {"grid": 64, "iterations": 1}}}}}, f)
            result = subprocess.run([sys.executable, os.path.join(os.path.dirname(HERE), "report.py"), d],
                                    capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertTrue(result.stdout.strip().endswith("report.md"))
            for name in ("time_vs_error_sine", "error_vs_iterations_sine", "fps_vs_grid_sine", "images_sine"):
                for ext in ("png", "pdf"):
                    path = os.path.join(d, "figures", f"{name}.{ext}")
                    self.assertTrue(os.path.getsize(path) > 1000, path)
            with open(os.path.join(d, "tables", "summary_sine.tex")) as f:
                tex = f.read()
            self.assertIn("\\toprule", tex)
            self.assertIn("relative\\_method (fit)", tex)
            with open(os.path.join(d, "report.md")) as f:
                report = f.read()
            self.assertIn("it broke", report)
            self.assertIn("(fit)", report)
            self.assertIn("raw nrmse (this sweep has no net error)", report)
            self.assertNotIn("no-caustic baseline |", report)  # no baseline column, so no baseline row
            self.assertNotIn(".tmp", " ".join(os.listdir(os.path.join(d, "figures"))))
            # report.html beside it: self-contained (every image a PNG data URI, nothing from the network),
            # with the sortable runs table and the truth-against-method comparison.
            import base64
            import html as html_module
            import re

            with open(os.path.join(d, "report.html")) as f:
                page = f.read()
            self.assertIsNone(re.search(r'(src|href)="(https?:)?//', page))
            uris = re.findall(r'data:image/png;base64,([A-Za-z0-9+/=]+)', html_module.unescape(page))
            self.assertGreaterEqual(len(uris), 1 + 2 * 3)   # the figure; truth, method and difference maps
            for uri in uris:
                self.assertEqual(base64.b64decode(uri)[:8], b"\x89PNG\r\n\x1a\n")
            self.assertIn('class="imagebox"', page)
            self.assertIn('type="range" class="wipe"', page)
            self.assertIn("<th>grid</th>", page)
            self.assertIn("relative_method (fit)", page)



# The no-caustic baseline's error per scene in the synthetic new-style sweep, and its reference noise.
BASELINE = {"sine": 0.3, "pool": 0.2}
NOISE = {"sine": 0.0, "pool": 0.01}


def new_style_rows():
    """Rows with issue 11's columns: sine has analytic truth, a run with net error 0 (interval [0, 0.004]),
    a non-radiometric method that is no better than the flat interface and one noisy timing; pool has a
    Monte Carlo reference whose noise (0.01) is half its smallest net error (0.02), above the 1/3 target."""
    rows = []

    def add(scene, method, radiometric, grid, iterations, net, lo, hi, **extra):
        render = 0.01 * grid * iterations
        frame_ms = render + 0.5  # an update cost, so the time axis can be told from the render time
        raw = net + 0.01
        run_id = f"{scene}-f0-{method}-grid={grid}-iterations={iterations}"
        rows.append(dict({
            "run_id": run_id, "scene": scene, "frame": 0, "method": method, "param.grid": grid,
            "param.iterations": iterations, "grid": grid, "iterations": iterations,
            "time_ms_median": render, "frame_time": "update+render", "frame_ms_median": frame_ms,
            "frame_ms_ci_rel": 0.01, "time_ms_stdev": 0.001, "time_ms_iqr": 0.001, "time_ms_ci_rel": 0.01,
            "render_fps": 1000 / render, "fps": 1000 / frame_ms, "noisy_timing": "false",
            "nrmse": raw if radiometric else 0.75, "nrmse_fit": raw, "fit_scale": 1.0 if radiometric else 4.0,
            "nrmse_net": net if radiometric else 0.7, "nrmse_net_lo": lo, "nrmse_net_hi": hi,
            "nrmse_fit_net": net, "nrmse_fit_net_lo": lo, "nrmse_fit_net_hi": hi,
            "error_kind": "nrmse" if radiometric else "nrmse_fit",
            "error_net": net, "error_net_lo": lo, "error_net_hi": hi,
            "baseline_error": BASELINE[scene], "error_vs_baseline": net / BASELINE[scene],
            "no_better_than_flat": "true" if net >= BASELINE[scene] else "false",
            "consistent_with_reference": "true" if lo == 0 else "false",
            "truth": "analytic:sine" if scene == "sine" else "reference", "noise_nrmse": NOISE[scene],
            "noise_target": "", "noise_target_met": "", "below_reference_noise": "true" if lo == 0 else "false",
            "radiometric": "true" if radiometric else "false", "status": "ok", "message": ""}, **extra))

    for grid in (32, 64, 128):
        for iterations in (1, 2, 3):
            net = 0.5 / grid ** 0.5 / iterations
            if (grid, iterations) == (128, 3):
                add("sine", "fast_method", True, grid, iterations, 0.0, 0.0, 0.004)
            else:
                add("sine", "fast_method", True, grid, iterations, net, 0.8 * net, 1.2 * net,
                    noisy_timing="true" if (grid, iterations) == (32, 1) else "false")
            bad = 0.35 + 0.01 * iterations
            add("sine", "relative_method", False, grid, iterations, bad, bad - 0.02, bad + 0.02)
    add("pool", "fast_method", True, 32, 1, 0.05, 0.04, 0.06)
    add("pool", "fast_method", True, 64, 1, 0.02, 0.015, 0.025)
    rows.append({k: "" for k in rows[0]} | {"run_id": "pool-f0-skipped", "scene": "pool", "method": "fast_method",
                                           "frame": 0, "radiometric": "true", "status": "skipped",
                                           "message": "not applicable"})
    return rows


def write_sweep(d, rows, report_settings):
    with open(os.path.join(d, "results.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    with open(os.path.join(d, "manifest.json"), "w") as f:
        json.dump({"host": {"cpu": "test cpu", "cores": 2}, "threads": 2, "build_type": "Release",
                   "git_commit": "abc", "spec": {"report": report_settings}}, f)


def section(report, scene):
    """The report.md text of one scene's section."""
    start = report.index(f"## {scene}\n")
    end = report.find("\n## ", start + 1)
    return report[start:] if end < 0 else report[start:end]


class NetErrorReportTest(unittest.TestCase):
    """A sweep with issue 11's columns: net errors with intervals, frame times, the baseline, truth and noise."""

    def run_report(self, d, report_settings):
        reference = 1.0 + 0.5 * np.sin(np.linspace(0, 6, 32))[None, :] * np.ones((32, 1))
        write_exr(os.path.join(d, "references", "sine-f0", "reference_receiver.exr"), reference)
        for row in new_style_rows():
            if row["scene"] == "sine":
                write_exr(os.path.join(d, "runs", row["run_id"], "receiver.exr"), reference * 1.01)
        write_sweep(d, new_style_rows(), report_settings)
        result = subprocess.run([sys.executable, os.path.join(os.path.dirname(HERE), "report.py"), d],
                                capture_output=True, text=True)
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(os.path.join(d, "report.md")) as f:
            return f.read()

    def test_report_states_truth_noise_ratio_baseline_and_flags(self):
        keep = os.environ.get("CAUSTICS_KEEP_REPORT_NET")  # a folder to keep the output in, for looking at it
        with tempfile.TemporaryDirectory() as tmp:
            d = keep or tmp
            report = self.run_report(d, {"paper_settings": {"fast_method": {"grid": 64, "iterations": 1}}})
            for name in ("time_vs_error_sine", "time_vs_error_pool", "error_vs_iterations_sine",
                         "fps_vs_grid_sine", "images_sine"):
                for ext in ("png", "pdf"):
                    path = os.path.join(d, "figures", f"{name}.{ext}")
                    self.assertTrue(os.path.getsize(path) > 1000, path)
            # Captions name the net error with its interval and the per-frame cost, and the drawn-at-floor run.
            self.assertIn("Error axis: net error (reference noise removed), 95 % interval drawn as vertical bars",
                          report)
            self.assertIn("Time axis: frame time = update + render for animated scenes", report)
            self.assertIn("1 run(s) with net error 0 (circled)", section(report, "sine"))
            self.assertIn("Dashed line: no-caustic baseline (flat interface), net error 0.3", report)
            # Per scene: truth, noise, smallest net error, ratio; pool is flagged, sine (analytic) is not.
            sine, pool = section(report, "sine"), section(report, "pool")
            self.assertIn("Truth: analytic closed form (sine); reference noise nrmse 0.", sine)
            self.assertIn("noise / smallest net error = 0 (target <= 0.333), 0 because the truth is analytic", sine)
            self.assertNotIn("FLAGGED", sine)
            self.assertIn("Truth: Monte Carlo reference; reference noise nrmse 0.01.", pool)
            self.assertIn("Smallest net error reported: 0.02 (fast_method); noise / smallest net error = 0.5", pool)
            self.assertIn("FLAGGED", pool)
            self.assertIn("flagged scenes: pool", report)
            self.assertIn("Of 18 ok runs: 1 below the reference noise (95 % interval includes 0), 1 with noisy "
                          "timing, 9 no better than the no-caustic baseline.", sine)
            # Tables: net error first, then raw; the baseline row without a time; the flat-interface mark.
            with open(os.path.join(d, "tables", "summary_sine.md")) as f:
                md = f.read()
            self.assertIn("| method | runs | best net error <= 16.7 ms | raw error (same run) |", md)
            self.assertIn("| no-caustic baseline | -- | 0.3 | -- | -- | -- | 0.3 |", md)
            self.assertIn("| relative_method (fit) | 9 | 0.36† |", md)
            self.assertIn("| fast_method | 9 | 0‡ | 0.01 |", md)  # the zero run, below the reference noise
            self.assertIn("† no better than the no-caustic baseline.", md)
            self.assertIn("| no-caustic baseline | -- | 0.3 |", report)
            with open(os.path.join(d, "tables", "summary_sine.tex")) as f:
                tex = f.read()
            self.assertIn("no-caustic baseline & -- & 0.3", tex)
            self.assertIn("0.36$^\\dagger$", tex)
            self.assertIn("$^\\dagger$ no better than the no-caustic baseline", tex)

    def test_noise_ratio_target_comes_from_the_spec(self):
        with tempfile.TemporaryDirectory() as d:
            report = self.run_report(d, {"noise_ratio_target": 0.6})
            self.assertNotIn("FLAGGED", report)
            self.assertIn("(target <= 0.6)", section(report, "pool"))


class TimeVsErrorAxesTest(unittest.TestCase):
    """What the time-vs-error figure draws, read back from its Axes."""

    def setUp(self):
        import pandas as pd

        from load import add_derived_columns

        self.frame = add_derived_columns(pd.DataFrame(new_style_rows()).replace("", np.nan))

    def test_error_bars_baseline_and_zero_error_run(self):
        import matplotlib.pyplot as plt

        from figures import BASELINE_LABEL, draw_time_vs_error, error_bar_extents

        fig, ax = plt.subplots()
        info = draw_time_vs_error(ax, self.frame, "sine")
        runs = self.frame[self.frame["scene"] == "sine"]
        positive = np.concatenate([runs[c].to_numpy(float) for c in ("error_net", "error_net_lo", "error_net_hi")])
        floor = 0.5 * positive[positive > 0].min()
        self.assertAlmostEqual(info["floor"], floor)
        self.assertEqual(info["clipped"], 1)
        # One vertical bar per run, at the frame time (not the render time), spanning the 95 % interval.
        bars = error_bar_extents(ax)
        self.assertEqual(len(bars), len(runs))
        for row in runs.itertuples():
            lo = max(row.error_net_lo, floor)
            self.assertTrue(any(np.isclose(x, row.frame_ms_median) and np.isclose(a, lo)
                                and np.isclose(b, row.error_net_hi) for x, a, b in bars), row.run_id)
        # The net-error-0 run is drawn at the floor, inside the axis limits, not dropped by the log axis.
        zero = runs[runs["error_net"] == 0].iloc[0]
        drawn = np.concatenate([c.get_offsets() for c in ax.collections if len(c.get_offsets())])
        self.assertTrue(any(np.allclose(p, (zero["frame_ms_median"], floor)) for p in drawn))
        self.assertLessEqual(ax.get_ylim()[0], floor)
        # The no-caustic baseline is a labelled horizontal line at the scene's baseline error.
        lines = [line for line in ax.get_lines() if line.get_label() == BASELINE_LABEL]
        self.assertEqual(len(lines), 1)
        self.assertTrue(np.allclose(lines[0].get_ydata(), BASELINE["sine"]))
        self.assertIn("net error (reference noise removed), 95 % interval", ax.get_ylabel())
        self.assertIn("frame time = update + render for animated scenes", ax.get_xlabel())
        plt.close(fig)

    def test_error_is_net_where_present_else_raw(self):
        import pandas as pd

        from load import add_derived_columns

        frame = add_derived_columns(pd.DataFrame([
            {"run_id": "a", "scene": "s", "method": "m", "status": "ok", "radiometric": "true", "nrmse": 0.2,
             "nrmse_fit": 0.1, "time_ms_median": 2.0, "frame_ms_median": 3.0, "error_net": 0.15,
             "error_net_lo": 0.1, "error_net_hi": 0.2},
            {"run_id": "b", "scene": "s", "method": "m", "status": "ok", "radiometric": "false", "nrmse": 0.2,
             "nrmse_fit": 0.1, "time_ms_median": 2.0, "frame_ms_median": np.nan, "error_net": np.nan,
             "error_net_lo": np.nan, "error_net_hi": np.nan}]))
        self.assertEqual(list(frame["error"]), [0.15, 0.1])
        self.assertEqual(list(frame["error_raw"]), [0.2, 0.1])
        self.assertEqual(list(frame["frame_ms"]), [3.0, 2.0])
        self.assertEqual(list(frame["error_is_net"]), [True, False])
        self.assertEqual(list(frame["label"]), ["m", "m (fit)"])


if __name__ == "__main__":
    unittest.main()


class MachineLineTest(unittest.TestCase):
    def test_load_at_start_and_end_and_the_busy_warning(self):
        import report

        quiet = {"start": {"busy": 0.04, "load_average": [0.12, 0.3, 0.4], "governor": "performance", "cores": 2},
                 "end": {"busy": 0.1, "load_average": [1.9, 1.0, 0.6], "cores": 2}, "loaded": False}
        line = report.machine_line({"machine": quiet})
        self.assertIn("4% busy (load 0.12) at the start, 10% busy (load 1.90) at the end", line)
        self.assertIn("governor performance", line)
        self.assertNotIn("Warning", line)
        busy = dict(quiet, loaded=True)
        # A resumed part that started on a busy machine flags the sweep; a part cut off has no end.
        line = report.machine_line({"machine": dict(quiet, end=None), "resumed": [{"machine": busy}]})
        self.assertIn("at the start, ? at the end; 4% busy (load 0.12) at the start, 10% busy", line)
        self.assertIn("Warning: the machine was busy", line)
        self.assertEqual(report.machine_line({}), "")   # sweeps that did not record it
        self.assertIn("Machine:", report.context_line({"machine": busy}))
        self.assertIn("Warning", report.context_line({"machine": busy}))
