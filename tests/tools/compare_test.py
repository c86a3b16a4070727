#!/usr/bin/python3
"""Tests of tools/compare.py: the Mann-Whitney U test against known values, and the command's
verdicts, messages and exit codes on synthetic Google Benchmark JSON made here (seeded random
numbers, so every run sees the same data).

usage: /usr/bin/python3 compare_test.py <tools dir>     (registered with ctest as compare_tool)
"""

import json
import math
import os
import random
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools")
COMPARE = os.path.join(TOOLS, "compare.py")
sys.path.insert(0, TOOLS)
import compare  # noqa: E402  (the path is only known at run time)

# Reference values computed once with scipy 1.10.1 (Debian bookworm's python3-scipy):
#   scipy.stats.mannwhitneyu(x, y, alternative="two-sided", method=M) -> (statistic, pvalue)
# (compare.py now calls scipy; these pin the values and the method it chooses).
MWU_REFERENCE = [
    # (x, y, method, U of x, p)
    ([1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30],
     [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.07, 3.14, 1.28],
     "exact", 58.0, 0.13591114767585355),
    ([1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30],
     [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.07, 3.14, 1.28],
     "asymptotic", 58.0, 0.1333202155896274),
    # Ties within y (1.06, 1.06; 1.29, 1.29): tie correction.
    ([1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30],
     [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29],
     "asymptotic", 58.0, 0.13291945818531892),
    ([10.1, 10.4, 9.8, 10.0, 10.3, 9.9, 10.2, 10.6, 9.7, 10.5],
     [11.0, 10.9, 11.3, 10.8, 11.5, 11.1, 10.7, 11.2, 11.4, 11.6],
     "exact", 0.0, 1.082508822446903e-05),
    ([10.1, 10.4, 9.8, 10.0, 10.3, 9.9, 10.2, 10.6, 9.7, 10.5],
     [11.0, 10.9, 11.3, 10.8, 11.5, 11.1, 10.7, 11.2, 11.4, 11.6],
     "asymptotic", 0.0, 0.00018267179110955002),
    # Ties (2, 2; 5, 5; 6, 6): the normal approximation with tie correction.
    ([3, 4, 2, 6, 2, 5], [9, 7, 5, 10, 6, 8], "asymptotic", 2.0, 0.012591911490379705),
    # Unequal sizes (9 and 11).
    ([1.1, 2.2, 3.3, 4.4, 5.5, 6.6, 7.7, 8.8, 9.9],
     [1.15, 2.25, 3.35, 4.45, 5.55, 6.65, 7.75, 8.85, 9.95, 10.05, 0.5],
     "exact", 45.0, 0.7664324839247441),
    ([1.1, 2.2, 3.3, 4.4, 5.5, 6.6, 7.7, 8.8, 9.9],
     [1.15, 2.25, 3.35, 4.45, 5.55, 6.65, 7.75, 8.85, 9.95, 10.05, 0.5],
     "asymptotic", 45.0, 0.7612079858009609),
]


class MannWhitneyTest(unittest.TestCase):
    def test_against_scipy_reference_values(self):
        for x, y, method, u, p in MWU_REFERENCE:
            with self.subTest(x=x[:3], method=method):
                got_u, got_p, used = compare.mann_whitney_u(x, y, method)
                self.assertEqual(used, method)
                self.assertEqual(got_u, u)
                self.assertAlmostEqual(got_p, p, delta=1e-12 + 1e-9 * p)

    def test_textbook_exact_distribution(self):
        # Complete separation of 3 and 3: 2 of the 20 arrangements are as extreme, p = 2 / 20.
        _, p, _ = compare.mann_whitney_u([1, 2, 3], [4, 5, 6], "exact")
        self.assertAlmostEqual(p, 0.1)
        # m = n = 3: the 20 arrangements give U = 0..9 with counts 1,1,2,3,3,3,3,2,1,1. Here
        # U of x = 2 (2.5 and 3 above 2), so p = 2 P(U <= 2) = 2 (1 + 1 + 2) / 20.
        u, p, _ = compare.mann_whitney_u([1, 2.5, 3], [2, 4, 5], "exact")
        self.assertEqual(u, 2.0)
        self.assertAlmostEqual(p, 2 * 4 / 20)

    def test_auto_method_and_degenerate_input(self):
        self.assertEqual(compare.mann_whitney_u([1, 2, 3], [4, 5, 6])[2], "exact")
        self.assertEqual(compare.mann_whitney_u([1, 2, 2], [4, 5, 6])[2], "asymptotic")
        self.assertEqual(compare.mann_whitney_u([1, 1, 1], [1, 1])[1], 1.0)
        with self.assertRaises(ValueError):
            compare.mann_whitney_u([1, 2, 2], [3, 4], "exact")

    def test_symmetric(self):
        x, y = [1.0, 3.5, 2.25, 8.0, 4.5], [2.0, 5.0, 6.5, 7.0, 9.5, 10.0]
        self.assertAlmostEqual(compare.mann_whitney_u(x, y)[1], compare.mann_whitney_u(y, x)[1])

    def test_base_name(self):
        self.assertEqual(compare.base_name("a/quadrant/n:1000/threads:1/iterations:1/real_time"),
                         "a/quadrant/n:1000/threads:1")
        self.assertEqual(compare.base_name("a/b/n:1/threads:2/repeats:9/manual_time"),
                         "a/b/n:1/threads:2")
        self.assertEqual(compare.base_name("a/b/n:1/threads:2"), "a/b/n:1/threads:2")


# ---- Synthetic Google Benchmark JSON ----------------------------------------------------------

SUFFIX = "/iterations:1/real_time"
STEPS = 60


def bench_rows(name, ms_values, counters=True, suffix=SUFFIX, **extra):
    """Per-repetition rows as quadrant_bench writes them, plus aggregate rows whose values are
    deliberately absurd: a tool that reads them instead of the repetitions gets wrong verdicts."""
    full = name + suffix
    rows = []
    for i, ms in enumerate(ms_values):
        row = {"name": full, "family_index": 0, "per_family_instance_index": 0, "run_name": full,
               "run_type": "iteration", "repetitions": len(ms_values), "repetition_index": i,
               "threads": 1, "iterations": 1, "real_time": ms * STEPS, "cpu_time": ms * STEPS,
               "time_unit": "ms"}
        if counters:
            row.update({"ms_per_step": ms, "steps_per_second": 1000.0 / ms, "steps": STEPS})
        row.update(extra)
        rows.append(row)
    for agg in ("mean", "median", "stddev", "cv"):
        rows.append({"name": f"{full}_{agg}", "run_name": full, "run_type": "aggregate",
                     "aggregate_name": agg, "repetitions": len(ms_values), "threads": 1,
                     "iterations": len(ms_values), "real_time": 1e9, "cpu_time": 1e9,
                     "time_unit": "ms", "ms_per_step": 1e9, "steps_per_second": 1e-9})
    return rows


def noisy(rng, center, n, noise):
    """n times around `center`: multiplicative noise of relative spread `noise`, with a right
    tail (preemption) on some repetitions, as real timings have."""
    out = []
    for _ in range(n):
        v = center * (1 + rng.gauss(0, noise))
        if rng.random() < 0.15:
            v += center * noise * rng.random() * 2
        out.append(max(v, center * 0.05))
    return out


def gbench(rows, commit="abc1234", **context):
    ctx = {"date": "2024-01-01T00:00:00+00:00", "commit": commit, "machine": "test-machine",
           "compiler": "GCC 12.2.0", "library_build_type": "release"}
    ctx.update(context)
    return {"context": ctx, "benchmarks": rows}


class CompareCommandTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory(prefix="quadrant-compare-test.")
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def write(self, name, data):
        path = os.path.join(self.dir, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "w", encoding="utf-8") as f:
            if isinstance(data, str):
                f.write(data)
            else:
                json.dump(data, f)
        return path

    def run_compare(self, *args):
        proc = subprocess.run([sys.executable, COMPARE, *args], capture_output=True, text=True,
                              timeout=120)
        return proc.returncode, proc.stdout, proc.stderr

    @staticmethod
    def verdict(stdout, name):
        """The verdict column of `name`'s table row."""
        for line in stdout.splitlines():
            if line.startswith(f"| {name} "):
                return line.rstrip(" |").split("|")[-1].strip().strip("*")
        raise AssertionError(f"no table row for {name} in:\n{stdout}")

    @staticmethod
    def named_after_table(stdout):
        """Names listed in the SLOWER section after the table."""
        lines = stdout.splitlines()
        names, inside = [], False
        for line in lines:
            if line.startswith("SLOWER"):
                inside = True
            elif inside and line.startswith("  - "):
                names.append(line[4:].rsplit(" (", 1)[0])
            elif inside:
                inside = False
        return names

    def test_same_distribution_is_unchanged(self):
        rng = random.Random(7)
        base_rows, new_rows, names = [], [], []
        for k, reps in enumerate((9, 12, 15)):
            name = f"circle_stress/quadrant/n:{1000 * (k + 1)}/threads:1"
            names.append(name)
            base_rows += bench_rows(name, noisy(rng, 2.0 + k, reps, 0.05))
            new_rows += bench_rows(name, noisy(rng, 2.0 + k, reps + 1, 0.05))
        code, out, err = self.run_compare(self.write("base.json", gbench(base_rows)),
                                          self.write("new.json", gbench(new_rows)))
        self.assertEqual(code, 0, out + err)
        for name in names:
            self.assertEqual(self.verdict(out, name), "unchanged", out)
        self.assertIn("No benchmark is slower.", out)
        self.assertEqual(self.named_after_table(out), [])

    def test_thirty_percent_slower_is_flagged_and_named(self):
        rng = random.Random(11)
        slow, steady = "polygon_stress/quadrant/n:1000/threads:1", "circle_stress/quadrant/n:1000/threads:1"
        base = bench_rows(slow, noisy(rng, 4.0, 9, 0.10)) + bench_rows(steady, noisy(rng, 2.0, 9, 0.10))
        new = bench_rows(slow, noisy(rng, 5.2, 9, 0.10)) + bench_rows(steady, noisy(rng, 2.0, 9, 0.10))
        code, out, err = self.run_compare(self.write("base.json", gbench(base)),
                                          self.write("new.json", gbench(new)))
        self.assertEqual(code, 1, out + err)
        self.assertEqual(self.verdict(out, slow), "slower", out)
        self.assertEqual(self.verdict(out, steady), "unchanged", out)
        self.assertEqual(self.named_after_table(out), [slow], out)
        # The aggregate rows are neither benchmarks of their own nor repetitions.
        for agg in ("_mean", "_median", "_stddev", "_cv"):
            self.assertNotIn(agg, out)
        self.assertEqual(out.count("| 9/9 |"), 2, out)

        # The same data the other way round: faster, exit 0.
        code, out, err = self.run_compare(os.path.join(self.dir, "new.json"),
                                          os.path.join(self.dir, "base.json"))
        self.assertEqual(code, 0, out + err)
        self.assertEqual(self.verdict(out, slow), "faster", out)

    def test_small_significant_change_stays_under_threshold(self):
        rng = random.Random(3)
        name = "circle_stress/quadrant/n:4000/threads:1"
        base = bench_rows(name, noisy(rng, 10.0, 12, 0.004))
        new = bench_rows(name, noisy(rng, 10.3, 12, 0.004))  # 3 % slower, far above the noise
        b, n = self.write("base.json", gbench(base)), self.write("new.json", gbench(new))
        code, out, err = self.run_compare(b, n)
        self.assertEqual(code, 0, out + err)
        self.assertEqual(self.verdict(out, name), "unchanged", out)
        # The change is significant: with a 1 % threshold it is reported.
        code, out, err = self.run_compare(b, n, "--threshold", "1")
        self.assertEqual(code, 1, out + err)
        self.assertEqual(self.verdict(out, name), "slower", out)

    def test_too_few_repetitions(self):
        rng = random.Random(5)
        name = "circle_stress/quadrant/n:1000/threads:1"
        b = self.write("base.json", gbench(bench_rows(name, noisy(rng, 2.0, 6, 0.01))))
        n = self.write("new.json", gbench(bench_rows(name, noisy(rng, 3.0, 6, 0.01))))
        code, out, err = self.run_compare(b, n)
        self.assertEqual(code, 3, out + err)  # inconclusive: its own status, not "unchanged"
        self.assertIn("INCONCLUSIVE", out)
        self.assertIn("a verdict needs 9 repetitions per side, BASE has 6 and NEW 6", out)
        self.assertNotIn(f"| {name} ", out)  # not tested: in the summary line, not the table
        code, out, err = self.run_compare(b, n, "--all")
        self.assertEqual(code, 3, out + err)
        self.assertEqual(self.verdict(out, name), "inconclusive (too few repetitions)", out)
        code, out, err = self.run_compare(b, n, "--min-repetitions", "6")
        self.assertEqual(code, 1, out + err)
        self.assertEqual(self.verdict(out, name), "slower", out)

    def test_many_untested_benchmarks_are_one_short_line(self):
        # The issue: a default bench (3 repetitions) against the committed one gave 158
        # "inconclusive" rows ending in one 6,776-character line.
        rng = random.Random(17)
        base, new = [], []
        for k in range(158):
            name = f"circle_stress/engine{k}/n:1000/threads:1"
            base += bench_rows(name, noisy(rng, 2.0, 3, 0.05))
            new += bench_rows(name, noisy(rng, 2.0, 3, 0.05))
        code, out, err = self.run_compare(self.write("base.json", gbench(base)),
                                          self.write("new.json", gbench(new)))
        self.assertEqual(code, 3, out + err)
        self.assertNotIn("| circle_stress/", out)
        summary = [line for line in out.splitlines() if line.startswith("Not tested (158 benchmarks")]
        self.assertEqual(len(summary), 1, out)
        self.assertIn("a verdict needs 9 repetitions per side, BASE has 3 and NEW 3", summary[0])
        self.assertIn("--repetitions 9", summary[0])
        self.assertLess(max(len(line) for line in out.splitlines()), 400, out)
        self.assertLess(len(out.splitlines()), 12, out)

    def loaded_pair(self, new_context, new_extra, faster=0.75):
        """Four benchmarks, 9 repetitions each: BASE quiet, NEW `faster` times with NEW's
        context and row counters as given."""
        rng = random.Random(23)
        base, new = [], []
        for n in (1000, 2000, 4000, 8000):
            name = f"circle_stress/quadrant/n:{n}/threads:1"
            base += bench_rows(name, noisy(rng, n / 500, 9, 0.03), others_cpu=0.05)
            new += bench_rows(name, noisy(rng, faster * n / 500, 9, 0.03), **new_extra)
        quiet = {"cores": "2", "load_avg_before": "0.30", "busy_processes": "0"}
        return (self.write("base.json", gbench(base, **quiet)),
                self.write("new.json", gbench(new, **{**quiet, **new_context})))

    def test_loaded_side_gives_no_faster_verdict(self):
        # The issue: bench --baseline then bench --compare of the same binary at load 5.2 said
        # all 4 benchmarks were 14-39 % faster (p down to 4e-5) and exited 0.
        b, n = self.loaded_pair({"load_avg_before": "5.20"}, {"others_cpu": 0.1})
        code, out, err = self.run_compare(b, n)
        self.assertEqual(code, 4, out + err)  # inconclusive (loaded), not 0
        for k in (1000, 2000, 4000, 8000):
            self.assertEqual(self.verdict(out, f"circle_stress/quadrant/n:{k}/threads:1"),
                             "inconclusive (loaded; looked faster)", out)
        self.assertNotIn("**faster**", out)
        self.assertNotIn("Faster (", out)
        self.assertIn("NEW ran loaded", out)
        self.assertIn("load average 5.20 before the run, above the 2 cores", out)
        self.assertIn("INCONCLUSIVE (loaded) (4)", out)
        # Asked for (both sides under the same load): the verdict, marked.
        code, out, err = self.run_compare(b, n, "--allow-load")
        self.assertEqual(code, 0, out + err)
        self.assertEqual(self.verdict(out, "circle_stress/quadrant/n:1000/threads:1"), "faster (loaded)", out)

    def test_other_processes_during_repetitions_withhold_the_verdict(self):
        # A quiet start, then a neighbour's compiler: others_cpu on NEW's repetitions.
        b, n = self.loaded_pair({}, {"others_cpu": 1.4}, faster=1.3)
        code, out, err = self.run_compare(b, n)
        self.assertEqual(code, 4, out + err)
        self.assertEqual(self.verdict(out, "circle_stress/quadrant/n:1000/threads:1"),
                         "inconclusive (loaded; looked slower)", out)
        self.assertNotIn("SLOWER", out)
        # The run's own busy loops (bench --busy 1) are not someone else's load.
        b, n = self.loaded_pair({"busy_processes": "1"}, {"others_cpu": 1.3}, faster=1.0)
        code, out, err = self.run_compare(b, n)
        self.assertEqual(code, 0, out + err)

    def test_directories_suffixes_real_time_and_one_sided_benchmarks(self):
        rng = random.Random(13)
        shared = "circle_stress/quadrant/n:2000/threads:1"
        values = noisy(rng, 3.0, 10, 0.05)
        # BASE: a directory of two files, whose repetitions are pooled; only real_time (no
        # counters); a benchmark NEW does not have.
        self.write("base/part1.json", gbench(bench_rows(shared, values[:5], counters=False)))
        self.write("base/part2.json", gbench(
            bench_rows(shared, values[5:], counters=False)
            + bench_rows("circle_stress/box2d/n:2000/threads:1", [1.0] * 9)))
        # NEW: the same name without Google Benchmark's suffix; a benchmark BASE does not have.
        self.write("new/run.json", gbench(
            bench_rows(shared, [v * 1.5 for v in noisy(rng, 3.0, 10, 0.05)], counters=False, suffix="")
            + bench_rows("circle_stress/chipmunk/n:2000/threads:1", [1.0] * 9)))
        code, out, err = self.run_compare(os.path.join(self.dir, "base"), os.path.join(self.dir, "new"))
        self.assertEqual(code, 1, out + err)
        self.assertEqual(self.verdict(out, shared + " (real_time)"), "slower", out)
        self.assertIn("| 10/10 |", out)
        self.assertIn("Only in BASE (not compared) (1): circle_stress/box2d/n:2000/threads:1", out)
        self.assertIn("Only in NEW (not compared) (1): circle_stress/chipmunk/n:2000/threads:1", out)

    def test_bad_input_exits_2_with_a_message(self):
        name = "circle_stress/quadrant/n:1000/threads:1"
        good = self.write("good.json", gbench(bench_rows(name, [1.0] * 9)))
        cases = {
            "missing file": (os.path.join(self.dir, "missing.json"), "no such file"),
            "not JSON": (self.write("text.json", "this is not { json"), "not valid JSON"),
            "no benchmarks array": (self.write("nobench.json", {"context": {}}),
                                    "not Google Benchmark JSON"),
            "JSON list": (self.write("list.json", [1, 2, 3]), "not Google Benchmark JSON"),
            "empty directory": (os.path.join(self.dir, "emptydir"), "no *.json"),
            "no common benchmarks": (self.write("other.json", gbench(
                bench_rows("polygon_stress/bullet/n:8000/threads:1", [1.0] * 9))),
                "no benchmark in common"),
        }
        os.makedirs(os.path.join(self.dir, "emptydir"))
        for label, (path, message) in cases.items():
            for args in ((good, path), (path, good)):
                with self.subTest(case=label, args=args):
                    code, out, err = self.run_compare(*args)
                    self.assertEqual(code, 2, out + err)
                    self.assertIn(message, err)
                    self.assertIn("compare: error:", err)


if __name__ == "__main__":
    unittest.main(verbosity=2)
