#!/usr/bin/python3
"""Tests of the scaling model (tools/scaling.py): the replay of recorded sections on P workers
against answers worked out by hand (each fails if the claiming rules or the costs are wrong), the
command on a synthetic recording, and, given the recording program, a smoke run of a real
recording on a small scene and of tools/quadrant scaling on it.

usage: /usr/bin/python3 scaling_test.py <tools dir> [<quadrant_scaling_trace>]
       (registered with ctest as scaling_model)
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools")
TRACE_BIN = os.path.abspath(sys.argv.pop(1)) if len(sys.argv) > 1 else None
sys.path.insert(0, TOOLS)
import scaling  # noqa: E402  (the path is only known at run time)

FREE = scaling.Params.free()


def costs(**kw):
    """Free costs but the given ones (handover, barrier, claim, wake, wake_call, spin)."""
    p = scaling.Params.free()
    for k, v in kw.items():
        setattr(p, k, v)
    return p


def job(threads, stages, runs, params=FREE, idle_for=0.0):
    """One job on a fresh pool whose workers have been idle for `idle_for` us."""
    pool = scaling.Pool(threads, params)
    pool.serial(idle_for)
    return pool.job(stages, runs)


def step(*sections):
    return {"us": 0, "sections": list(sections)}


def serial(us, stage="solve"):
    return {"kind": "serial", "stage": stage, "us": us}


def region(stages, runs=True, stage="solve"):
    return {"kind": "region", "stage": stage, "runs": runs, "span_us": 0, "us": stages}


def pfor(blocks, stage="narrow_phase"):
    return {"kind": "for", "stage": stage, "span_us": 0, "us": [blocks]}


class Replay(unittest.TestCase):
    def test_equal_chunks_share_evenly(self):
        # 4 chunks of 1 on 2 workers: 2 each, makespan 2 (not 4, not 1).
        self.assertEqual(job(2, [[1, 1, 1, 1]], True), (2.0, 1))
        self.assertEqual(job(2, [[1, 1, 1, 1]], False), (2.0, 1))
        self.assertEqual(job(4, [[1, 1, 1, 1]], False), (1.0, 1))
        # Fewer chunks than workers: one chunk is the floor.
        self.assertEqual(job(16, [[1, 1, 1, 1]], False), (1.0, 1))

    def test_any_thread_claims_any_block(self):
        # Blocks 3, 1, 1, 1 on 2 workers: the caller takes block 0 (3), the worker (odd, from the
        # back) blocks 3, 2 and 1 as it frees up: 3. Blocks bound to threads (0-1 and 2-3) take 4.
        self.assertEqual(job(2, [[3, 1, 1, 1]], False)[0], 3.0)
        # The caller from the front, odd workers from the back: with 2 workers on 1, 1, 1, 3 the
        # worker takes the 3 first and the caller the three 1s: 3, not 4 (both from the front:
        # caller 1 then 1, worker 1 then 3 ends at 4).
        self.assertEqual(job(2, [[1, 1, 1, 3]], False)[0], 3.0)

    def test_runs_of_chunks(self):
        # 6 chunks on 2 workers, claimShare 4. In runs (a region's default) the caller's first
        # claim takes ceil(6 / 4) = 2 chunks, 6 + 2, while the worker does the four 1s: makespan
        # 8. One chunk a claim (a parallel-for, a region whose plan says runs = false) the caller
        # takes the 6 and the worker the rest, 2 + 1 + 1 + 1 + 1: makespan 6.
        chunks = [6, 2, 1, 1, 1, 1]
        self.assertEqual(job(2, [chunks], True)[0], 8.0)
        self.assertEqual(job(2, [chunks], False)[0], 6.0)

    def test_stages_and_barriers_add(self):
        # Two stages of 4 x 1 on 2 workers: 2 + 2; each stage's end a barrier of 0.5.
        self.assertEqual(job(2, [[1, 1, 1, 1], [1, 1, 1, 1]], True), (4.0, 2))
        self.assertEqual(job(2, [[1, 1, 1, 1], [1, 1, 1, 1]], True, costs(barrier=0.5)), (5.0, 2))
        # A stage of no items is skipped: no barrier.
        self.assertEqual(job(2, [[1, 1], [], [1, 1]], True, costs(barrier=0.5)), (3.0, 2))
        # A stage waits for its longest chunk even with idle threads.
        self.assertEqual(job(4, [[5, 1], [1, 1, 1, 1]], True)[0], 6.0)

    def test_handover_and_claims(self):
        # The worker starts 0.5 late: caller 0-1 (chunk 0), worker 0.5-1.5 (chunk 3), caller 1-2
        # (chunk 1), worker 1.5-2.5 (chunk 2).
        self.assertEqual(job(2, [[1, 1, 1, 1]], False, costs(handover=0.5))[0], 2.5)
        # Claims go through one word one at a time: 4 workers, 4 chunks of 1, a claim 0.25:
        # granted at 0, 0.25, 0.5, 0.75, the last done at 0.75 + 0.25 + 1.
        self.assertEqual(job(4, [[1, 1, 1, 1]], False, costs(claim=0.25))[0], 2.0)

    def test_sleeping_workers(self):
        # After 2000 us alone the worker sleeps (spin 1000) and needs 100 us to wake: the caller
        # runs both chunks of 10 (20), plus the futex wake it pays (2).
        p = costs(wake=100.0, spin=1000.0, wake_call=2.0)
        self.assertEqual(job(2, [[10, 10]], False, p, idle_for=2000.0)[0], 22.0)
        # Idle for less than the spin: it comes at once (no handover cost here).
        self.assertEqual(job(2, [[10, 10]], False, p, idle_for=500.0)[0], 10.0)


class Model(unittest.TestCase):
    def test_serial_sections_add_and_fractions(self):
        steps = [step(serial(3), region([[1, 1, 1, 1]]), {"kind": "gap", "us": 1})]
        out = scaling.model_steps(steps, 2, FREE)
        self.assertEqual(out["us"], 3 + 2 + 1)
        self.assertEqual(out["serial_us"], 4)
        self.assertEqual(out["work_us"], 4)
        self.assertEqual(out["barriers"], 1)
        self.assertEqual(out["handovers"], 1)
        self.assertEqual(out["stage_us"]["outside"], 1)
        # At one thread the chunks run one after another, with no job.
        one = scaling.model_steps(steps, 1, costs(barrier=5, handover=5))
        self.assertEqual(one["us"], 8)
        self.assertEqual(one["barriers"], 0)

    def test_for_is_one_block_a_claim(self):
        # A parallel-for's blocks are never claimed in runs.
        steps = [step(pfor([6, 2, 1, 1, 1, 1]))]
        self.assertEqual(scaling.model_steps(steps, 2, FREE)["us"], 6)
        steps = [step(region([[6, 2, 1, 1, 1, 1]], runs=True))]
        self.assertEqual(scaling.model_steps(steps, 2, FREE)["us"], 8)
        steps = [step(region([[6, 2, 1, 1, 1, 1]], runs=False))]
        self.assertEqual(scaling.model_steps(steps, 2, FREE)["us"], 6)

    def test_command_on_a_synthetic_recording(self):
        # 1 thread: 10 serial + 8 of region work = 18. 2 threads: 10 serial, then a region of
        # 2 stages of 4 x 1 (2 + 2, two barriers of 1) = 16: speed-up 18 / 16, s = 10 / 18.
        trace = {"scene": "synthetic", "count": 1, "bodies": 1, "traces": [
            {"threads": 1, "steps": [step(serial(10), serial(8))]},
            {"threads": 2, "steps": [step(serial(10), region([[1, 1, 1, 1], [1, 1, 1, 1]]))]},
        ]}
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "trace.json")
            with open(path, "w", encoding="utf-8") as f:
                json.dump(trace, f)
            out = os.path.join(tmp, "out")
            r = subprocess.run([sys.executable, os.path.join(TOOLS, "scaling.py"), "--trace", path,
                                "--threads", "2", "--out", out, "--handover-us", "0", "--claim-us", "0",
                                "--barrier-us", "1", "--wake-us", "0", "--wake-call-us", "0"],
                               capture_output=True, text=True, check=False,
                               env=dict(os.environ, QUADRANT_MACHINE="test-2c", QUADRANT_COMMIT="abc1234"))
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "scaling.json"), encoding="utf-8") as f:
                result = json.load(f)
            # The context results/README.md reads: where, at which commit, when, against what.
            self.assertEqual(result["context"]["machine"], "test-2c")
            self.assertEqual(result["context"]["commit"], "abc1234")
            self.assertRegex(result["context"]["date"], r"^\d{4}-\d\d-\d\dT")
            row = result["cases"][0]["threads"]["2"]
            self.assertAlmostEqual(row["speedup"], 18 / 16)
            self.assertAlmostEqual(row["serial_fraction"], 10 / 18)
            self.assertAlmostEqual(row["amdahl"], 1 / (10 / 18 + (8 / 18) / 2))
            self.assertEqual(row["barriers"], 2)
            self.assertAlmostEqual(row["sync_ms"], 0.002)
            self.assertTrue(os.path.exists(os.path.join(out, "scaling.md")))
            # A recording without the 1-thread trace is refused (exit 2, one line).
            trace["traces"].pop(0)
            with open(path, "w", encoding="utf-8") as f:
                json.dump(trace, f)
            r = subprocess.run([sys.executable, os.path.join(TOOLS, "scaling.py"), "--trace", path],
                               capture_output=True, text=True, check=False)
            self.assertEqual(r.returncode, 2)
            self.assertIn("no 1-thread trace", r.stderr)


    def test_measured_reference_json(self):
        # The synthetic case measured at 36 us at 1 thread (the median of 30, 36 and 40; the peer's
        # and the aggregate rows ignored) and 24 us at 2: the recording is scaled by 36 / 18 = 2, so
        # 2 threads take 20 serial + 2 stages x (4 + a barrier of 1, not scaled) = 30 us, a
        # predicted 36 / 30 = 1.2 against the measured 36 / 24 = 1.5.
        trace = {"scene": "synthetic", "count": 1, "bodies": 1, "traces": [
            {"threads": 1, "steps": [step(serial(10), serial(8))]},
            {"threads": 2, "steps": [step(serial(10), region([[1, 1, 1, 1], [1, 1, 1, 1]]))]},
        ]}
        def row(threads, ms, engine="quadrant"):
            return {"name": f"synthetic/{engine}/n:1/threads:{threads}", "run_type": "iteration",
                    "run_name": f"synthetic/{engine}/n:1/threads:{threads}/iterations:1/real_time",
                    "ms_per_step": ms}
        bench = {"context": {"machine": "m16", "commit": "abc"}, "benchmarks": [
            row(1, 0.030), row(1, 0.036), row(1, 0.040), row(2, 0.024),
            row(1, 9.0, "box2d"), {"name": "x_median", "run_type": "aggregate", "ms_per_step": 1.0}]}
        with tempfile.TemporaryDirectory() as tmp:
            path, ref = os.path.join(tmp, "trace.json"), os.path.join(tmp, "bench.json")
            with open(path, "w", encoding="utf-8") as f:
                json.dump(trace, f)
            with open(ref, "w", encoding="utf-8") as f:
                json.dump(bench, f)
            out = os.path.join(tmp, "out")
            r = subprocess.run([sys.executable, os.path.join(TOOLS, "scaling.py"), "--trace", path,
                                "--threads", "2", "--out", out, "--handover-us", "0", "--claim-us", "0",
                                "--barrier-us", "1", "--wake-us", "0", "--wake-call-us", "0", "--reference", ref],
                               capture_output=True, text=True, check=False)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(os.path.join(out, "scaling.json"), encoding="utf-8") as f:
                case = json.load(f)["cases"][0]
            self.assertAlmostEqual(case["one_thread_ms"], 0.036)
            self.assertAlmostEqual(case["threads"]["2"]["speedup"], 36 / 30)
            self.assertAlmostEqual(case["threads"]["2"]["measured_speedup"], 1.5)
            self.assertIn("machine m16, commit abc", r.stdout)
            # A reference that is not a bench JSON is refused (exit 2, one line).
            with open(ref, "w", encoding="utf-8") as f:
                f.write("[]")
            r = subprocess.run([sys.executable, os.path.join(TOOLS, "scaling.py"), "--trace", path,
                                "--reference", ref], capture_output=True, text=True, check=False)
            self.assertEqual(r.returncode, 2)
            self.assertIn("not a Google Benchmark JSON", r.stderr)


@unittest.skipUnless(TRACE_BIN, "needs the quadrant_scaling_trace binary")
class Recording(unittest.TestCase):
    def test_small_scene(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "trace.json")
            r = subprocess.run([TRACE_BIN, "--scene", "pyramid", "--count", "1275", "--threads", "2,4",
                                "--steps", "2", "--warmup", "2", "--repeats", "2", "--out", path],
                               capture_output=True, text=True, check=False)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(path, encoding="utf-8") as f:
                trace = json.load(f)
            self.assertEqual([t["threads"] for t in trace["traces"]], [1, 2, 4])  # 1 is always recorded
            for t in trace["traces"]:
                p = t["threads"]
                self.assertEqual(len(t["steps"]), 2)
                for s in t["steps"]:
                    kinds = {x["kind"] for x in s["sections"]}
                    if p == 1:  # one thread: no parallel section at all
                        self.assertFalse(kinds & {"for", "region"}, kinds)
                        continue
                    # A base-50 pyramid: the narrow phase is a parallel-for, the solver's colours regions.
                    self.assertIn("for", kinds)
                    self.assertIn("region", kinds)
                    for x in s["sections"]:
                        if x["kind"] == "for":
                            self.assertEqual([len(b) for b in x["us"]], [p])  # one block per thread
                        elif x["kind"] == "region":
                            self.assertTrue(all(len(c) <= 4 * p for c in x["us"]))  # StageChunks' most
                        if x["kind"] in ("for", "region"):
                            self.assertIn(x["stage"], scaling.STAGES)
            # The model reads it.
            r = subprocess.run([sys.executable, os.path.join(TOOLS, "scaling.py"), "--trace", path,
                                "--threads", "2,4"], capture_output=True, text=True, check=False)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("pyramid 1275", r.stdout)

    def test_driver(self):
        # tools/quadrant scaling with the built programs (QUADRANT_BIN_DIR: nothing is built).
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "out")
            env = dict(os.environ, QUADRANT_BIN_DIR=os.path.dirname(TRACE_BIN))
            r = subprocess.run(["bash", os.path.join(TOOLS, "quadrant"), "scaling", "--scenes", "pyramid",
                                "--counts", "210", "--threads", "2", "--steps", "1", "--warmup", "1",
                                "--repeats", "1", "--out", out], capture_output=True, text=True, env=env,
                               check=False)
            self.assertEqual(r.returncode, 0, r.stderr)
            for name in ("scaling.md", "scaling.json", "trace_pyramid_210.json"):
                self.assertTrue(os.path.exists(os.path.join(out, name)), name)
            self.assertIn("pyramid 210", r.stdout)
            # A bad option: one line, exit 2, nothing written.
            r = subprocess.run(["bash", os.path.join(TOOLS, "quadrant"), "scaling", "--threads", "2,,4",
                                "--out", os.path.join(tmp, "bad")], capture_output=True, text=True, env=env,
                               check=False)
            self.assertEqual(r.returncode, 2)
            self.assertEqual(len(r.stderr.strip().splitlines()), 1, r.stderr)
            self.assertFalse(os.path.exists(os.path.join(tmp, "bad")))


if __name__ == "__main__":
    unittest.main(argv=[sys.argv[0]])
