"""The README's generated method table (scripts/report/method_table.py): counts and worst errors from the drawn
cases' CSVs, the frame time at the defaults from a sweep, the block rewritten between its markers only."""
import io
import json
import os
import sys
import tempfile
import unittest
from contextlib import redirect_stderr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))

import method_table  # noqa: E402

HEADER = "method,seed,case,what,refused,inside,nrmse,baseline,bound\n"


class MethodTableTest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        d = self.dir.name
        self.drawn = os.path.join(d, "drawn")
        os.makedirs(self.drawn)
        with open(os.path.join(self.drawn, "m.csv"), "w") as f:
            f.write(HEADER)
            f.write('m,7,c0,"sine A 0.01 m, tilt 3 deg",0,1,0.02,0.4,0.1\n')
            f.write('m,7,c1,"sine, past focus",0,1,0.061,0.5,0.1\n')
            f.write('m,7,c2,"outside",0,0,0.9,0.5,\n')      # outside: its error is not the worst inside
            f.write('m,7,c3,"refused",1,0,,,\n')
        self.sweep = os.path.join(d, "sweep")
        os.makedirs(self.sweep)
        with open(os.path.join(self.sweep, "results.csv"), "w") as f:
            f.write("method,scene,status,param.grid,param.mode,frame_ms_median,time_ms_median\n")
            f.write("m,sine,ok,64,fast,1.0,1.0\n")
            f.write("m,sine,ok,128,fast,4.25,4.0\n")       # the default grid
            f.write("m,pool,ok,128,fast,99,99\n")          # another scene
            f.write("n,sine,ok,,,2.0,2.0\n")
        self.methods = os.path.join(d, "methods.json")
        with open(self.methods, "w") as f:
            json.dump({"methods": [{"name": "m", "params": [{"name": "grid", "default": 128},
                                                             {"name": "mode", "default": "fast"}]},
                                   {"name": "n", "params": [{"name": "grid", "default": 32}]}]}, f)
        self.claims = os.path.join(d, "claims.json")
        with open(self.claims, "w") as f:
            json.dump({"m": {"paper": "P", "claim": "0.10; anywhere"}, "n": {"paper": "Q", "claim": "0.2"}}, f)
        self.readme = os.path.join(d, "README.md")
        with open(self.readme, "w") as f:
            f.write(f"# title\n\nbefore\n\n{method_table.BEGIN}\nold table\n{method_table.END}\n\nafter\n")

    def tearDown(self):
        self.dir.cleanup()

    def read(self):
        with open(self.readme) as f:
            return f.read()

    def args(self, *extra):
        return ["--drawn", self.drawn, "--sweep", self.sweep, "--methods", self.methods, "--claims", self.claims,
                *extra]

    def test_counts_worst_and_default_time(self):
        self.assertEqual(method_table.main(self.args("--readme", self.readme)), 0)
        text = self.read()
        self.assertTrue(text.startswith("# title\n\nbefore\n\n"))
        self.assertTrue(text.endswith("\nafter\n"))
        self.assertNotIn("old table", text)
        self.assertIn("On 4 drawn cases (seed 7)", text)
        self.assertIn("| [m](methods/m/README.md) | P | 0.10; anywhere | 2 / 4 | 0.061 | 4.2 ms |", text)
        # no drawn cases for n; its run has no recorded grid, which counts as the default
        self.assertIn("| [n](methods/n/README.md) | Q | 0.2 | - | - | 2.0 ms |", text)
        # rewriting is idempotent: the block is replaced, not appended
        self.assertEqual(method_table.main(self.args("--readme", self.readme)), 0)
        self.assertEqual(self.read(), text)

    def test_missing_markers_and_unknown_method_exit_2(self):
        with open(self.readme, "w") as f:
            f.write("no markers\n")
        err = io.StringIO()
        with redirect_stderr(err):
            self.assertEqual(method_table.main(self.args("--readme", self.readme)), 2)
        self.assertIn("markers", err.getvalue())
        self.assertEqual(self.read(), "no markers\n")
        with open(self.claims, "w") as f:
            json.dump({"z": {"paper": "-", "claim": "-"}}, f)
        err = io.StringIO()
        with redirect_stderr(err):
            self.assertEqual(method_table.main(self.args()), 2)
        self.assertIn("'z'", err.getvalue())

    def test_cases_of_two_seeds_are_refused(self):
        with open(os.path.join(self.drawn, "m.csv"), "a") as f:
            f.write('m,8,c9,"x",0,1,0.01,0.4,0.1\n')
        err = io.StringIO()
        with redirect_stderr(err):
            self.assertEqual(method_table.main(self.args()), 2)
        self.assertIn("several seeds", err.getvalue())


if __name__ == "__main__":
    unittest.main()
