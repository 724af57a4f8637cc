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


class ReportTest(unittest.TestCase):
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
            self.assertNotIn(".tmp", " ".join(os.listdir(os.path.join(d, "figures"))))


if __name__ == "__main__":
    unittest.main()
