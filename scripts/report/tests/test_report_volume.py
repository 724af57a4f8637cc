"""The volume view's section of the report (camera_volume): table, image row, and its absence elsewhere."""
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
sys.path.insert(0, HERE)

from test_report import write_exr  # noqa: E402


def rows():
    out = []
    for scene, volume in (("fog", True), ("sine", False)):
        for grid in (16, 32):
            error = 0.4 / grid ** 0.5
            row = {"run_id": f"{scene}-f0-beams-grid={grid}", "scene": scene, "frame": 0, "method": "beams",
                   "param.grid": grid, "grid": grid, "iterations": 1, "time_ms_median": 0.1 * grid,
                   "nrmse": error, "error_net": error, "radiometric": "true", "status": "ok", "message": "",
                   "volume_nrmse": "", "volume_nrmse_net": "", "volume_baseline_error": ""}
            if volume:
                row.update({"volume_nrmse": 2 * error + 0.01, "volume_nrmse_net": 2 * error,
                            "volume_baseline_error": 0.9})
            out.append(row)
    return out


class VolumeReportTest(unittest.TestCase):
    def test_volume_section_where_measured_only(self):
        with tempfile.TemporaryDirectory() as d:
            reference = np.outer(np.linspace(0.0, 1.0, 24), np.ones(32))
            write_exr(os.path.join(d, "references", "fog-f0", "reference_camera_volume.exr"), reference)
            for row in rows():
                if row["scene"] == "fog":
                    write_exr(os.path.join(d, "runs", row["run_id"], "camera_volume.exr"), reference * 1.1)
            with open(os.path.join(d, "results.csv"), "w", newline="") as f:
                writer = csv.DictWriter(f, fieldnames=list(rows()[0].keys()))
                writer.writeheader()
                writer.writerows(rows())
            with open(os.path.join(d, "manifest.json"), "w") as f:
                json.dump({"spec": {"report": {}}}, f)
            result = subprocess.run([sys.executable, os.path.join(os.path.dirname(HERE), "report.py"), d],
                                    capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            with open(os.path.join(d, "report.md")) as f:
                report = f.read()
            fog = report[report.index("## fog"):report.index("## sine")]
            sine = report[report.index("## sine"):]
            self.assertIn("Volume caustics (camera_volume)", fog)
            self.assertNotIn("camera_volume", sine)
            # The best net error is grid 32's (2 x 0.4 / sqrt(32)), beside the constant baseline 0.9.
            self.assertIn(f"| beams | 2 | {2 * 0.4 / 32 ** 0.5:.3g} | 3.2 |", fog)
            self.assertIn("| 0.9 |", fog)
            for ext in ("png", "pdf"):
                self.assertGreater(os.path.getsize(os.path.join(d, "figures", f"volume_fog.{ext}")), 1000)
                self.assertGreater(os.path.getsize(os.path.join(d, "figures", f"volume_time_vs_error_fog.{ext}")), 1000)
            self.assertIn("volume_time_vs_error_fog.png", fog)
            self.assertFalse(os.path.exists(os.path.join(d, "figures", "volume_time_vs_error_sine.png")))
            self.assertTrue(os.path.exists(os.path.join(d, "tables", "volume_fog.md")))
            self.assertFalse(os.path.exists(os.path.join(d, "tables", "volume_sine.md")))

    def test_volume_plot_marks_the_pareto_front_and_labels_the_varied_parameter(self):
        import pandas as pd
        import matplotlib.pyplot as plt
        from volume import draw_volume_time_vs_error
        runs = pd.DataFrame({"label": ["beams"] * 3, "frame_ms": [10.0, 20.0, 40.0],
                             "volume_error": [0.5, 0.6, 0.2], "volume_error_is_net": [True] * 3,
                             "volume_baseline": [0.9] * 3, "param.step": [4, 2, 1], "param.grid": [16] * 3})
        fig, ax = plt.subplots()
        draw_volume_time_vs_error(ax, runs, "fog")
        steps = [line for line in ax.get_lines() if line.get_label().startswith("beams")]
        self.assertEqual(len(steps), 1)
        # (20 ms, 0.6) is beaten by (10 ms, 0.5): the front is the first and the last run.
        self.assertEqual(list(steps[0].get_xdata()), [10.0, 40.0])
        texts = sorted(t.get_text() for t in ax.texts)
        self.assertEqual(texts, ["step 1", "step 2", "step 4"])
        plt.close(fig)


if __name__ == "__main__":
    unittest.main()
