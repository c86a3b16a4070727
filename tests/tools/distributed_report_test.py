#!/usr/bin/python3
"""Tests of tools/distributed_report.py on synthetic runs: repeated runs collapse to their median
run with its range; efficiencies, ceilings and World ratios are medians of each repetition's own
ratios (not ratios of medians); the independent runs fill the ceiling columns and make no table of
their own; a threads column appears where a rank has more threads; a jacobi hash that differs
across rank counts is flagged; every table's rows have the header's columns.

usage: /usr/bin/python3 distributed_report_test.py <tools dir>   (registered with ctest as distributed_report)
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools")
SCRIPT = os.path.join(TOOLS, "distributed_report.py")


def run_row(**kw):
    row = {"scene": "circle_stress", "solver": "soft_step", "ranks": 1, "bodies": 16004, "steps": 100, "warmup": 100,
           "tiles": 16, "iterations": 8, "threads": 1, "weak": True, "independent": False, "ms_per_step": 1.0,
           "rounds_per_step": 11, "bytes_per_step": 0.0, "bytes_per_boundary_body": 0.0, "shadow_fraction": 0.0,
           "imbalance": 1.0, "state_hash": "0000000000000001", "oversubscribed": False, "cores": 2,
           "peak_rss_mb": 40.0, "rss_bytes_per_body": 2500,
           "stage_ms": {"halo": [0.2, 0.2], "collide": [0.5, 0.5], "wait": [0.0, 0.0]}}
    row.update(kw)
    return row


def weak_runs():
    """Three repetitions of 1 rank, 2 ranks and 2 independent worlds, chosen so that the median
    of the paired ratios differs from the ratio of the medians."""
    one, two, alone = [1.0, 1.2, 1.3], [2.0, 1.5, 1.6], [1.25, 1.3, 1.2]
    runs = []
    for rep in range(3):
        runs.append(run_row(repetition=rep + 1, ms_per_step=one[rep], world_ms_per_step=one[rep] / (1.1 + 0.1 * rep)))
        runs.append(run_row(repetition=rep + 1, ranks=2, bodies=32004, ms_per_step=two[rep], state_hash="00000000000000a2"))
        runs.append(run_row(repetition=rep + 1, ranks=2, bodies=32004, ms_per_step=alone[rep], independent=True,
                            rounds_per_step=2, state_hash="0000000000000001"))
    return runs


def report(runs):
    with tempfile.TemporaryDirectory(prefix="quadrant-distributed-report-test.") as d:
        path = os.path.join(d, "runs.jsonl")
        with open(path, "w") as f:
            for r in runs:
                f.write(json.dumps(r) + "\n")
        out_json, out_md = os.path.join(d, "distributed.json"), os.path.join(d, "distributed.md")
        subprocess.run([sys.executable, SCRIPT, path, "--machine", "test", "--commit", "abc", "--json", out_json,
                        "--md", out_md], check=True, capture_output=True, text=True)
        with open(out_md) as f:
            md = f.read()
        with open(out_json) as f:
            data = json.load(f)
    return md, data


def tables(md):
    """Each table as its header, separator and rows, split into cells."""
    lines = md.split("\n")
    found = []
    for i, line in enumerate(lines):
        if line.startswith("|---") and i > 0:
            rows = []
            for row in lines[i + 1:]:
                if not row.startswith("|"):
                    break
                rows.append(row)
            found.append((lines[i - 1], line, rows))
    return found


class Repetitions(unittest.TestCase):
    def setUp(self):
        self.md, self.data = report(weak_runs())

    def weak_row(self, ranks):
        for header, _, rows in tables(self.md):
            if "efficiency" in header:
                for row in rows:
                    cells = [c.strip() for c in row.strip("|").split("|")]
                    if cells[0] == str(ranks):
                        return dict(zip([c.strip() for c in header.strip("|").split("|")], cells))
        self.fail(f"no weak-scaling row for {ranks} ranks in:\n{self.md}")

    def test_median_run_and_range(self):
        self.assertEqual(self.weak_row(2)["ms/step"], "1.60 (1.50-2.00)")
        self.assertEqual(self.weak_row(1)["ms/step"], "1.20 (1.00-1.30)")

    def test_efficiency_is_the_median_of_paired_ratios(self):
        # pairs 1.0/2.0, 1.2/1.5, 1.3/1.6: median 0.80; the medians' ratio would be 1.2/1.6 = 75 %
        self.assertEqual(self.weak_row(2)["efficiency"], "80 %")

    def test_ceiling_from_the_independent_runs(self):
        row = self.weak_row(2)
        self.assertEqual(row["independent ms/step"], "1.25 (1.20-1.30)")
        self.assertEqual(row["ceiling"], "92 %")  # 1.0/1.25, 1.2/1.3, 1.3/1.2
        self.assertEqual(row["of ceiling"], "75 %")  # 1.25/2.0, 1.3/1.5, 1.2/1.6

    def test_independent_runs_make_no_table(self):
        self.assertEqual(sum("weak scaling" in h for h in self.md.split("\n") if h.startswith("## ")), 1)

    def test_world_ratio_is_the_median_of_the_runs_ratios(self):
        # ratios 1.1, 1.2, 1.3: the median run's own ratio (1.2) and the median agree here; the
        # line says it is a median
        self.assertIn("1.20x (medians).", self.md)

    def test_raw_runs_kept_in_the_json(self):
        self.assertEqual(len(self.data["runs"]), 9)


class Columns(unittest.TestCase):
    def test_every_row_has_the_headers_columns(self):
        runs = weak_runs()
        runs += [run_row(weak=False, bodies=64004, ranks=r, threads=t, ms_per_step=8.0 / r)
                 for r, t in ((1, 16), (4, 4), (16, 1))]
        runs += [run_row(solver="jacobi", weak=False, scene="pyramid", bodies=211, ranks=r, ms_per_step=0.8,
                         apex_drift_m=0.01, state_hash="000000000000000%d" % r) for r in (1, 2)]
        md, _ = report(runs)
        for header, separator, rows in tables(md):
            n = header.count("|")
            self.assertEqual(separator.count("|"), n, f"{header}\n{separator}")
            for row in rows:
                self.assertEqual(row.count("|"), n, f"{header}\n{row}")
        self.assertIn("| ranks | threads |", md)
        self.assertIn("(differs!)", md)  # jacobi's hash must not depend on the rank count


if __name__ == "__main__":
    unittest.main()
