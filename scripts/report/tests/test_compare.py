"""`caustics compare` (scripts/report/compare.py) on hand-made sweep folders: runs matched by scene, frame,
method and parameters; SAME for samples of one distribution (the false-positive rate stays near alpha over
many draws), SLOWER for a 20 % slowdown, WORSE and BETTER for error changes beyond their intervals;
unmatched runs listed; warnings when the machines differ; exit 3 with --fail-on-regression, 2 for bad
input with nothing written."""
import io
import json
import math
import os
import sys
import tempfile
import unittest
from contextlib import redirect_stderr, redirect_stdout

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import compare  # noqa: E402


def row(method, samples, error, half=0.0, grid=64, scene="sine"):
    return {"scene": scene, "frame": 0, "method": method, "params": {"grid": grid}, "status": "ok",
            "radiometric": True, "frame_ms": {"median": float(np.median(samples)), "samples": list(samples)},
            "error": {"receiver": {"nrmse_net": error, "nrmse_net_lo": error - half, "nrmse_net_hi": error + half}}}


def write_sweep(directory, rows, cpu="AMD EPYC", loaded=False):
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, "results.jsonl"), "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    with open(os.path.join(directory, "manifest.json"), "w") as f:
        json.dump({"host": {"cpu": cpu, "cores": 2}, "threads": 2, "build_type": "Release", "git_commit": "abc",
                   "machine": {"loaded": loaded}}, f)


def quiet(fn, *args):
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = fn(*args)
    return code, out.getvalue(), err.getvalue()


class MannWhitneyTest(unittest.TestCase):
    def test_false_positive_rate_near_alpha(self):
        rng = np.random.default_rng(20261206)
        alpha, trials = 0.05, 400
        hits = sum(compare.mann_whitney_p(rng.lognormal(0, 0.1, 12), rng.lognormal(0, 0.1, 12)) < alpha
                   for _ in range(trials))
        # Binomial(400, <= 0.05): mean <= 20, sd about 4.4; the continuity correction makes it conservative.
        self.assertLessEqual(hits, 35)
        self.assertGreaterEqual(hits, 5)

    def test_a_shift_is_found_and_ties_are_handled(self):
        rng = np.random.default_rng(3)
        a = rng.lognormal(0, 0.05, 12)
        self.assertLess(compare.mann_whitney_p(a, a * 1.2), 1e-3)
        self.assertEqual(compare.mann_whitney_p([1.0] * 5, [1.0] * 5), 1.0)
        self.assertEqual(compare.mann_whitney_p([1.0], [2.0, 3.0]), 1.0)
        # Small exact case against the normal approximation's value (scipy's asymptotic method agrees).
        self.assertAlmostEqual(compare.mann_whitney_p([1, 2, 3], [4, 5, 6]), 0.0808556, places=6)


class CompareSweepsTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.base = os.path.join(self.dir.name, "base")
        self.new = os.path.join(self.dir.name, "new")
        self.out = os.path.join(self.dir.name, "out")
        rng = np.random.default_rng(7)
        self.a = rng.lognormal(np.log(10), 0.03, 15)
        self.b = rng.lognormal(np.log(10), 0.03, 15)

    def tearDown(self):
        self.dir.cleanup()

    def run_compare(self, *extra):
        return quiet(compare.main, [self.base, self.new, "--out", self.out, *extra])

    def table(self):
        import csv

        with open(os.path.join(self.out, "compare.csv")) as f:
            return {(r["method"], r["params"]): r for r in csv.DictReader(f)}

    def test_same_slower_worse_better_and_unmatched(self):
        write_sweep(self.base, [row("m", self.a, 0.10, 0.002), row("slow", self.a, 0.10),
                                row("worse", self.a, 0.10, 0.002), row("better", self.a, 0.10, 0.002),
                                row("gone", self.a, 0.1)])
        write_sweep(self.new, [row("m", self.b, 0.1005, 0.002), row("slow", self.b * 1.2, 0.10),
                               row("worse", self.b, 0.12, 0.002), row("better", self.b, 0.08, 0.002),
                               row("m", self.b, 0.1, grid=128)])
        code, out, _ = self.run_compare()
        self.assertEqual(code, 0)
        t = self.table()
        g64 = json.dumps({"grid": 64})
        self.assertEqual((t[("m", g64)]["time"], t[("m", g64)]["error"]), ("SAME", "SAME"))
        self.assertEqual(t[("slow", g64)]["time"], "SLOWER")
        self.assertAlmostEqual(float(t[("slow", g64)]["time_ratio"]), 1.2 * np.median(self.b) / np.median(self.a))
        self.assertEqual(t[("worse", g64)]["error"], "WORSE")
        self.assertEqual(t[("better", g64)]["error"], "BETTER")
        self.assertEqual(len(t), 4)
        with open(os.path.join(self.out, "compare.md")) as f:
            md = f.read()
        self.assertIn("Only in the base (1)", md)
        self.assertIn("gone", md)
        self.assertIn("Only in the new sweep (1)", md)
        self.assertTrue(os.path.getsize(os.path.join(self.out, "compare_time_vs_error.png")) > 1000)
        # The page: self-contained (the figure a PNG data URI, nothing from the network), every pair a row.
        import base64
        import re

        with open(os.path.join(self.out, "compare.html")) as f:
            page = f.read()
        self.assertIsNone(re.search(r'(src|href)="(https?:)?//', page))
        uris = re.findall(r'data:image/png;base64,([A-Za-z0-9+/=]+)', page)
        self.assertEqual(len(uris), 1)
        self.assertEqual(base64.b64decode(uris[0])[:8], b"\x89PNG\r\n\x1a\n")
        self.assertEqual(page.count("<tr>"), 1 + 4)
        self.assertIn("SLOWER", page)
        self.assertIn("only in the base", page)
        self.assertIn("1 only in the base", out)
        # A CI gate: the regressions give exit status 3.
        code, _, _ = self.run_compare("--fail-on-regression")
        self.assertEqual(code, 3)

    def test_a_sweep_against_itself_is_same_everywhere(self):
        write_sweep(self.base, [row("m", self.a, 0.1, 0.01), row("n", self.b, 0.2)])
        code, _, err = quiet(compare.main, [self.base, self.base, "--out", self.out, "--fail-on-regression"])
        self.assertEqual(code, 0)
        self.assertEqual({(r["time"], r["error"]) for r in self.table().values()}, {("SAME", "SAME")})
        self.assertEqual(err, "")

    def test_machine_differences_are_warned(self):
        write_sweep(self.base, [row("m", self.a, 0.1)])
        write_sweep(self.new, [row("m", self.b, 0.1)], cpu="Intel Xeon", loaded=True)
        code, _, err = self.run_compare()
        self.assertEqual(code, 0)
        self.assertIn("CPU differs", err)
        self.assertIn("busy machine", err)
        with open(os.path.join(self.out, "compare.md")) as f:
            self.assertIn("**Warning:** CPU differs", f.read())

    def test_bad_input_exits_2_and_writes_nothing(self):
        write_sweep(self.base, [row("m", self.a, 0.1)])
        code, _, err = self.run_compare()   # no new folder
        self.assertEqual(code, 2)
        self.assertIn("no results.jsonl", err)
        os.makedirs(self.new)
        with open(os.path.join(self.new, "results.jsonl"), "w") as f:
            f.write("{not json\n")
        code, _, err = self.run_compare()
        self.assertEqual(code, 2)
        self.assertIn("results.jsonl:1", err)
        code, _, err = quiet(compare.main, [self.base, self.base, "--out", self.out, "--alpha", "0"])
        self.assertEqual(code, 2)
        self.assertIn("--alpha", err)
        self.assertFalse(os.path.exists(self.out))


if __name__ == "__main__":
    unittest.main()
