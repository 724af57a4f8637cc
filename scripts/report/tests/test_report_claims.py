"""The report's accuracy-claim table: per method, the runs inside its claim, the bound they were held to and the
worst error measured inside it, on a hand-made frame."""
import os
import sys
import unittest

import numpy as np
import pandas as pd

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import quality  # noqa: E402


def frame(rows):
    base = {"scene": "sine", "status": "ok", "error": 0.1, "frame_ms": 1.0, "radiometric": True, "nrmse_fit": np.nan}
    return pd.DataFrame([{**base, **r} for r in rows])


class ClaimTableTest(unittest.TestCase):
    def test_worst_error_inside_and_whether_it_held(self):
        f = frame([
            {"method": "a", "claim_inside": True, "claim_max_error": 0.05, "claim_bound": 0.05, "nrmse": 0.02},
            {"method": "a", "claim_inside": True, "claim_max_error": 0.05, "claim_bound": 0.04, "nrmse": 0.03},
            {"method": "a", "claim_inside": False, "claim_max_error": np.nan, "claim_bound": np.nan, "nrmse": 0.9},
            # relative output: judged after the fit; the second run misses its bound
            {"method": "b", "radiometric": False, "claim_inside": True, "claim_max_error": 0.25, "claim_bound": 0.2,
             "nrmse": 5.0, "nrmse_fit": 0.1},
            {"method": "b", "radiometric": False, "claim_inside": True, "claim_max_error": 0.25, "claim_bound": 0.2,
             "nrmse": 5.0, "nrmse_fit": 0.3},
        ])
        rows = {r["method"]: r for r in quality.claim_rows(f, "sine")}
        self.assertEqual((rows["a"]["runs"], rows["a"]["inside"]), (3, 2))
        self.assertAlmostEqual(rows["a"]["worst"], 0.03)       # the run outside (0.9) is not counted
        self.assertAlmostEqual(rows["a"]["bound"], 0.05)
        self.assertTrue(rows["a"]["held"])
        self.assertAlmostEqual(rows["b"]["worst"], 0.3)        # nrmse_fit, not the raw 5.0
        self.assertFalse(rows["b"]["held"])
        lines = quality.claim_lines(quality.claim_rows(f, "sine"))
        self.assertIn("| b | 2 | 2 | 0.25 | 0.2 | 0.3 | **no** |", lines)

    def test_runs_without_a_judged_bound_show_dashes(self):
        f = frame([{"method": "c", "claim_inside": True, "claim_max_error": 0.1, "claim_bound": np.nan, "nrmse": 0.2}])
        self.assertIn("| c | 1 | 1 | 0.1 | -- | -- | -- |", quality.claim_lines(quality.claim_rows(f, "sine")))


if __name__ == "__main__":
    unittest.main()
