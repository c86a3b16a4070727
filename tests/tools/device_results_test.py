#!/usr/bin/python3
"""Tests of tools/device_results.py on a synthetic device call (needs no binary): the head's
sets merged into bench.json (a frame loop, another commit and a repeated benchmark left out),
the comparisons section, the refusals (no JSON; an out folder of another machine), and --ab (interleaved
pairs: only comparisons.md written, ratios per pair, hashes, frame loop against the pairs).

usage: /usr/bin/python3 device_results_test.py <tools dir>   (registered with ctest as device_results)
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools")
SCRIPT = os.path.join(TOOLS, "device_results.py")


def bench_set(path, commit, date, scene, threads, reps, steps, frame_rate="0", ms=2.0, label="0123456789abcdef"):
    rows = []
    for t in threads:
        for i in range(reps):
            v = ms / t * (1 + 0.01 * i)
            rows.append({"name": f"{scene}/quadrant/n:100/threads:{t}/iterations:1/real_time",
                         "run_name": f"{scene}/quadrant/n:100/threads:{t}/iterations:1/real_time",
                         "run_type": "iteration", "repetitions": reps, "repetition_index": i,
                         "real_time": v * steps, "time_unit": "ms", "ms_per_step": v, "steps": steps,
                         "warmup": 30, "steps_per_second": 1000 / v, "label": label,
                         "stage_solve_ms": v / 2})
    ctx = {"date": date, "commit": commit, "cpu_model": "Test CPU", "num_cpus": 4, "cores": "4",
           "machine": "Test CPU 4c", "scenes": scene, "engines": "quadrant",
           "thread_counts": ",".join(map(str, threads)), "steps": str(steps), "warmup": "30",
           "frame_rate": frame_rate, "counts": f"{scene}:100"}
    with open(path, "w") as f:
        json.dump({"context": ctx, "benchmarks": rows}, f)


def run(*args):
    r = subprocess.run(["/usr/bin/python3", SCRIPT, *args], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


class DeviceResults(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="quadrant-device-results-test.")
        self.addCleanup(shutil.rmtree, self.tmp)
        self.dir = os.path.join(self.tmp, "d1")
        os.makedirs(self.dir)
        d = self.dir
        bench_set(f"{d}/stress.json", "aaaaaaa", "2026-01-01T10:00:00+00:00", "circle_stress", [1, 2, 4], 3, 150)
        bench_set(f"{d}/thesis.json", "aaaaaaa", "2026-01-01T10:05:00+00:00", "circle_stress", [1, 3], 2, 120)
        bench_set(f"{d}/frame60.json", "aaaaaaa", "2026-01-01T10:03:00+00:00", "circle_stress", [1, 2], 1, 150,
                  frame_rate="60", ms=3.0)
        bench_set(f"{d}/stress_bbbbbbb.json", "bbbbbbb", "2026-01-01T10:01:00+00:00", "circle_stress", [1, 4], 2,
                  150, ms=4.0)
        with open(f"{d}/machine.txt", "w") as f:
            f.write("4\nModel name:  Test CPU\nNUMA node(s): 1\n")
        self.out = os.path.join(self.tmp, "results", "test-4c")

    def test_merge_and_comparisons(self):
        status, out = run(self.dir, "--machine", "test-4c", "--out", self.out, "--comparisons", "--no-index")
        self.assertEqual(status, 0, out)
        with open(os.path.join(self.out, "bench.json")) as f:
            data = json.load(f)
        ctx, rows = data["context"], data["benchmarks"]
        self.assertEqual(ctx["machine"], "test-4c")
        self.assertEqual(ctx["commit"], "aaaaaaa")
        # stress: 3 threads x 3 reps; thesis: only its 3-thread rows (its 1-thread ones repeat stress's)
        self.assertEqual(len(rows), 9 + 2)
        self.assertEqual({r["steps"] for r in rows if "threads:1/" in r["name"]}, {150})
        self.assertIn("120-150", ctx["steps"])
        self.assertIn("frame60.json", ctx["device_skipped"])
        self.assertIn("stress_bbbbbbb.json", ctx["device_skipped"])
        for name in ("speedup.md", "fps_circle_stress.png", "machine.txt", "comparisons.md"):
            self.assertTrue(os.path.isfile(os.path.join(self.out, name)), name)
        with open(os.path.join(self.out, "comparisons.md")) as f:
            text = f.read()
        self.assertIn("## 4 cores, aaaaaaa against bbbbbbb (one lent call, 2026-01-01)", text)
        self.assertIn("| aaaaaaa / bbbbbbb | | 0.50 | - | 0.50 |", text)  # 2/t against 4/t ms per step
        self.assertIn("60 Hz frame loop", text)
        # Rerun: the section is replaced, not added twice.
        status, out = run(self.dir, "--machine", "test-4c", "--out", self.out, "--comparisons", "--no-index")
        self.assertEqual(status, 0, out)
        with open(os.path.join(self.out, "comparisons.md")) as f:
            self.assertEqual(f.read().count("## 4 cores, aaaaaaa"), 1)

    def test_refuses_without_json(self):
        empty = os.path.join(self.tmp, "empty")
        os.makedirs(empty)
        status, out = run(empty, "--machine", "test-4c", "--out", self.out)
        self.assertEqual(status, 2, out)
        self.assertEqual(len(out.strip().splitlines()), 1, out)
        self.assertFalse(os.path.exists(self.out))

    def test_refuses_to_mix_machines(self):
        os.makedirs(self.out)
        with open(os.path.join(self.out, "bench.json"), "w") as f:
            json.dump({"context": {"machine": "other-2c", "num_cpus": 2}, "benchmarks": []}, f)
        status, out = run(self.dir, "--machine", "test-4c", "--out", self.out)
        self.assertEqual(status, 2, out)
        self.assertEqual(sorted(os.listdir(self.out)), ["bench.json"])

    def test_ab_pairs(self):
        d = os.path.join(self.tmp, "d2")
        os.makedirs(d)
        # Pair N: base (4/t ms) then head; head/base 0.5, 0.6, 0.4 at every thread count: median 0.50.
        for n, (b_ms, h_ms) in enumerate([(4.0, 2.0), (4.0, 2.4), (5.0, 2.0)], 1):
            bench_set(f"{d}/stress_base_{n}.json", "bbbbbbb", f"2026-01-02T10:0{2 * n}:00+00:00", "circle_stress",
                      [1, 2], 1, 150, ms=b_ms)
            bench_set(f"{d}/stress_head_{n}.json", "aaaaaaa", f"2026-01-02T10:0{2 * n + 1}:00+00:00", "circle_stress",
                      [1, 2], 1, 150, ms=h_ms, label="0123456789abcdef" if n < 3 else "ffffffffffffffff")
        bench_set(f"{d}/stress_base_4.json", "bbbbbbb", "2026-01-02T10:09:00+00:00", "circle_stress", [1], 1, 150)
        bench_set(f"{d}/frame60.json", "aaaaaaa", "2026-01-02T10:10:00+00:00", "circle_stress", [1, 2], 1, 150,
                  frame_rate="60", ms=4.4)
        bench_set(f"{d}/other.json", "aaaaaaa", "2026-01-02T10:11:00+00:00", "circle_stress", [1], 1, 150)
        with open(f"{d}/machine.txt", "w") as f:
            f.write("4\nModel name:  Test CPU\nNUMA node(s): 1\n")
        # An earlier call's folder: its bench.json must stay as it is.
        status, out = run(self.dir, "--machine", "test-4c", "--out", self.out, "--no-index")
        self.assertEqual(status, 0, out)
        with open(os.path.join(self.out, "bench.json")) as f:
            before = f.read()
        title = "4 cores, aaaaaaa against bbbbbbb: pairs"
        for _ in range(2):  # the rerun replaces the section
            status, out = run(d, "--machine", "test-4c", "--out", self.out, "--ab", "base", "head", "--title", title,
                              "--no-index")
            self.assertEqual(status, 0, out)
        with open(os.path.join(self.out, "bench.json")) as f:
            self.assertEqual(f.read(), before)
        with open(os.path.join(self.out, "comparisons.md")) as f:
            text = f.read()
        self.assertEqual(text.count("## " + title), 1)
        # 1 thread: base median 4.000, head 2.000; ratios 0.50 / 0.60 / 0.40; solve = ms / 2.
        self.assertIn("| circle_stress/quadrant/n:100 | 1 | 4.000 | 2.000 | 0.50 | 0.50 / 0.60 / 0.40 | "
                      "2.000 -> 1.000 | no: base `01234567`, head `01234567`/`ffffffff` | - |", text)
        self.assertIn("base first in every pair", text)
        self.assertIn("stress_base_4.json (no head set of pair 4)", text)
        self.assertIn("`other.json`", text)
        self.assertIn("4.000 against 2.020 ms (x1.98)", text)  # 1 thread: the earlier call: 2.0 * (1, 1.01, 1.02)
        self.assertIn("ran slower than the earlier call's", text)
        # Frame loop 4.4/t against the head's back-to-back median 2.0/t.
        self.assertIn("| ratio | 2.20 | 2.20 |", text)
        # Refusals: equal tags; no pair.
        status, out = run(d, "--machine", "test-4c", "--out", self.out, "--ab", "head", "head")
        self.assertEqual(status, 2, out)
        status, out = run(d, "--machine", "test-4c", "--out", self.out, "--ab", "old", "new")
        self.assertEqual(status, 2, out)
        self.assertEqual(len(out.strip().splitlines()), 1, out)


if __name__ == "__main__":
    unittest.main()
