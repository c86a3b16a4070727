#!/usr/bin/python3
"""Tests of tools/results_index.py: the committed results/README.md lists every file under
results/ (the check CI runs), and the check fails on a tree whose index misses a file or lists
one that is gone (made here in temporary checkouts, with and without git).

usage: /usr/bin/python3 results_index_test.py <source root>   (registered with ctest as results_index)
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCRIPT = os.path.join(ROOT, "tools", "results_index.py")
PYTHON = "/usr/bin/python3"


def run(root, *args):
    r = subprocess.run([PYTHON, SCRIPT, "--root", root, *args], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


class CommittedIndex(unittest.TestCase):
    def test_results_readme_lists_every_file(self):
        status, out = run(ROOT, "--check")
        self.assertEqual(status, 0, "results/README.md is not up to date with results/ "
                         "(regenerate it: tools/quadrant results-index):\n" + out)


class Check(unittest.TestCase):
    """A small results/ tree: written, checked, then a file added and one removed."""

    def setUp(self):
        self.root = tempfile.mkdtemp(prefix="quadrant-results-index-test.")
        self.addCleanup(shutil.rmtree, self.root)
        m = os.path.join(self.root, "results", "test-machine")
        os.makedirs(os.path.join(m, "sub"))
        with open(os.path.join(m, "bench.json"), "w") as f:
            json.dump({"context": {"date": "2026-01-02T03:04:05+00:00", "commit": "abc1234",
                                   "cpu_model": "Test CPU", "num_cpus": 2}, "benchmarks": []}, f)
        for name in ("speedup.md", "fps_circle_stress.png", "sub/notes.md"):
            with open(os.path.join(m, name), "w") as f:
                f.write("# a heading\n")
        with open(os.path.join(self.root, "results", "history.csv"), "w") as f:
            f.write("record,date,commit,machine\n1,2026-01-02T03:04:05Z,abc1234,test-machine\n")

    def write_and_check(self):
        status, out = run(self.root)
        self.assertEqual(status, 0, out)
        with open(os.path.join(self.root, "results", "README.md")) as f:
            text = f.read()
        self.assertIn("[`bench.json`](test-machine/bench.json)", text)
        self.assertIn("2026-01-02 03:04 UTC", text)
        self.assertIn("`abc1234`", text)
        self.assertIn("CPU Test CPU", text)
        self.assertIn("[`sub/notes.md`](test-machine/sub/notes.md)", text)
        self.assertNotIn("README.md`]", text)  # not listed in itself
        status, out = run(self.root, "--check")
        self.assertEqual(status, 0, out)

        # A new file not in the index: the check fails and names it.
        new = os.path.join(self.root, "results", "test-machine", "fps_pyramid.png")
        with open(new, "w") as f:
            f.write("png")
        status, out = run(self.root, "--check")
        self.assertEqual(status, 1, out)
        self.assertIn("results/test-machine/fps_pyramid.png is not in results/README.md", out)
        os.remove(new)
        self.assertEqual(run(self.root, "--check")[0], 0)

        # A listed file that is gone: the check fails and names it.
        os.remove(os.path.join(self.root, "results", "test-machine", "speedup.md"))
        status, out = run(self.root, "--check")
        self.assertEqual(status, 1, out)
        self.assertIn("lists results/test-machine/speedup.md, which is not there", out)

        # No index at all: fails.
        os.remove(os.path.join(self.root, "results", "README.md"))
        self.assertEqual(run(self.root, "--check")[0], 1)

    def test_outside_git(self):
        # A failed run's folder and the baselines are not part of the record.
        os.makedirs(os.path.join(self.root, "results", "baselines"))
        with open(os.path.join(self.root, "results", "baselines", "test-machine.json"), "w") as f:
            f.write("{}")
        os.makedirs(os.path.join(self.root, "results", "test-machine.failed-20260101T000000Z"))
        with open(os.path.join(self.root, "results", "test-machine.failed-20260101T000000Z", "x.json"), "w") as f:
            f.write("{}")
        self.write_and_check()
        self.assertEqual(run(self.root)[0], 0)
        with open(os.path.join(self.root, "results", "README.md")) as f:
            text = f.read()
        self.assertNotIn("baselines", text.split("## results/ (all machines)")[-1])
        self.assertNotIn("failed-2026", text)

    @unittest.skipIf(shutil.which("git") is None, "git not installed")
    def test_in_git(self):
        subprocess.run(["git", "init", "-q", self.root], check=True)
        with open(os.path.join(self.root, ".gitignore"), "w") as f:
            f.write("results/baselines/\n")
        os.makedirs(os.path.join(self.root, "results", "baselines"))
        with open(os.path.join(self.root, "results", "baselines", "test-machine.json"), "w") as f:
            f.write("{}")
        self.write_and_check()


if __name__ == "__main__":
    unittest.main(verbosity=2)
