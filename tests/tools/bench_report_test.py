#!/usr/bin/python3
"""tools/bench_report.py at the defaults and under noise (issue #29 items 2 and 5), on the committed
runs (results/*/bench.json) and on a copy of one made noisy (load 5.6 before the run, every
fourth benchmark's repetitions spread 200 %), drawn into a temporary directory:

- the plots: one panel per thread count, no text or legend over another or off the figure
  (bench_report.layout_problems), a one-line footer that lists no flagged point;
- speedup.md: its warnings before the first figure, noisy figures marked in the ratio tables
  too, the bound shown only where measured and a bound of 1.00 said as such.

usage: /usr/bin/python3 bench_report_test.py ROOT     (registered with ctest as bench_report)
"""

import copy
import glob
import json
import os
import re
import sys
import tempfile
import unittest

ROOT = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tools"))
import bench_report  # noqa: E402
import gbench_json  # noqa: E402

RECORDED = sorted(glob.glob(os.path.join(ROOT, "results", "*", "bench.json")))


def noisy_copy(path):
    """The run as if made on a loaded machine: load 5.6 before it, every fourth benchmark with
    a repetition three times slower."""
    data = gbench_json.load(path)
    data = copy.deepcopy(data)
    data["context"]["load_avg_before"] = "5.60"
    seen, extra = set(), []
    for row in data["benchmarks"]:
        name = row.get("run_name", row["name"])
        if row.get("run_type") != "iteration" or name in seen:
            continue
        seen.add(name)
        if len(seen) % 4 == 0:
            slow = copy.deepcopy(row)
            slow["real_time"] *= 3
            slow["steps_per_second"] /= 3
            extra.append(slow)
    data["benchmarks"] += extra
    return data


class ReportTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="quadrant-bench-report-test.")

    def tearDown(self):
        self.tmp.cleanup()

    def draw(self, data):
        results = bench_report.Results(data)
        problems = {}
        for scene in results.scenes:
            path = os.path.join(self.tmp.name, f"fps_{scene}.png")
            problems[scene] = bench_report.plot_scene(results, scene, path)
            self.assertGreater(os.path.getsize(path), 10000, path)
        return results, problems

    def test_recorded_runs_draw_cleanly(self):
        self.assertTrue(RECORDED, "no results/*/bench.json")
        for path in RECORDED:
            with self.subTest(run=os.path.relpath(path, ROOT)):
                results, problems = self.draw(gbench_json.load(path))
                for scene, found in problems.items():
                    self.assertEqual(found, [], f"{scene}: {found}")

    def test_noisy_run_draws_cleanly_with_a_one_line_footer(self):
        data = noisy_copy(RECORDED[0])
        results, problems = self.draw(data)
        flagged = bench_report.flags(results)
        self.assertGreater(len(flagged), 10)
        for scene, found in problems.items():
            self.assertEqual(found, [], f"{scene}: {found}")
            footer = bench_report.plot_footer(results, scene)
            self.assertNotIn("\n", footer)
            self.assertIn("FLAGGED: ", footer)
            self.assertIn("noisy point", footer)
            self.assertIn("load 5.60 before the run", footer)
            self.assertLess(len(footer), 260, footer)  # the count, not the list of points
            self.assertNotIn(" n=", footer)

    def test_speedup_md_opens_with_its_warnings(self):
        data = noisy_copy(RECORDED[0])
        results = bench_report.Results(data)
        text = bench_report.markdown(results, "bench.json")
        lines = text.splitlines()
        first_table = next(i for i, line in enumerate(lines) if line.startswith("|"))
        head = "\n".join(lines[:first_table])
        self.assertIn("**Warning: every figure below is flagged**: load average 5.60", "\n".join(lines[:5]))
        self.assertRegex("\n".join(lines[:6]), r"\*\*Warning: \d+ of \d+ benchmark figures are noisy\*\*")
        self.assertIn("Reading the speed-ups", head)
        # The ratio tables: a ratio of a flagged figure is marked, and the table says the whole
        # run is flagged.
        ratios = text[text.index("/ peer (1 thread), steps-per-second ratio"):]
        self.assertIn("**Every ratio here is flagged**", ratios)
        self.assertRegex(ratios, r"\| \d+ \| [^\n]*\d\.\d\d \(\*\*noisy\*\*\)")
        flagged = bench_report.flags(results)
        for scene, engine, n, t in flagged:
            if t == 1 and engine.startswith("quadrant") and not engine.count(":"):
                row = re.search(rf"^\| {n} \| (.*) \|$", ratios[ratios.index(f"### {scene}"):], re.M)
                self.assertTrue(row and "(**noisy**)" in row.group(1), f"{scene} {n}: {row and row.group(0)}")

    def test_bound_only_where_measured(self):
        self.assertEqual(bench_report.speedup_cell(1.5, None), "1.50x")
        self.assertEqual(bench_report.speedup_cell(1.5, 1.83), "1.50x (bound 1.83)")
        self.assertEqual(bench_report.speedup_cell(2.4, 1.83), "2.40x (bound 1.83; noise)")
        self.assertEqual(bench_report.speedup_cell(0.98, 1.0), "0.98x (work on 1 thread)")
        self.assertEqual(bench_report.speedup_cell(2.0, 1.0), "2.00x (work on 1 thread; noise)")
        text = bench_report.markdown(bench_report.Results(gbench_json.load(RECORDED[0])), "bench.json")
        self.assertNotIn("(bound 1.00)", text)
        for line in text.splitlines():
            if line.startswith("| Chipmunk") or line.startswith("| Box2D") or line.startswith("| Bullet"):
                self.assertNotIn("bound", line)


if __name__ == "__main__":
    unittest.main(verbosity=2)
