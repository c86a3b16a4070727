#!/usr/bin/python3
"""The scaling model: a step's speed-up at P threads predicted from a recording of its structure.

Usage (driven by tools/quadrant scaling, which builds quadrant_scaling_trace and records first):

    /usr/bin/python3 tools/scaling.py --trace FILE [--trace FILE ...] [--threads 2,4,8,16]
        [--out DIR] [--handover-us U] [--barrier-us U] [--claim-us U] [--wake-us U]
        [--wake-call-us U] [--spin-us U] [--reference 16c|none] [--fit SCENE:COUNT,...]
    /usr/bin/python3 tools/scaling.py --record BINARY --out DIR [--scenes a,b] [--counts a,b]
        [--steps S] [--warmup W] [--repeats R] [model options as above]
        (records each case into DIR/trace_<scene>_<count>.json with BINARY, a
        quadrant_scaling_trace, then models them as above; the default cases are the reference's)

A trace (benchmarks/scaling_trace.cpp) holds, per thread count P and step, in order: the serial
sections (the stage runner's inline sections, and the gaps between sections: the step's code
outside the runner), the parallel-fors (one time per static block: P of them) and the regions of
stages (per stage, one time per chunk: StageChunks' up to 4 P), all timed on one core.

The model replays each step on P workers as the pool (engine/src/parallel/thread_pool.cpp) runs
it:
- a serial section or gap runs on the caller; the workers wait, spinning for --spin-us, then
  asleep;
- a parallel section is a job: the caller publishes it (paying --wake-call-us, a futex wake, when
  a worker sleeps) and claims at once; each worker starts --handover-us later, or --wake-us later
  if it was asleep;
- within a stage every thread, the caller included, claims from the unclaimed chunks
  [front, back) whenever it is free: the caller and even workers from the front, odd workers
  from the back; one chunk a claim in a parallel-for and in a region whose plan forbids runs,
  otherwise a run of ceil(left / 2P) chunks (claimShare: 2 x threads); claims go through one
  word, one at a time, --claim-us each;
- a stage ends when its last chunk does; every thread starts the next stage --barrier-us later
  (the last stage's end is the job's join, a barrier too), a thread that waited more than
  --spin-us at it --wake-us later still.
Ties go to the lower thread index (the caller first). Not in the model: the pool's own judgement
of the machine (a pool that runs alone after misfiring load checks), memory bandwidth and cache
effects (a chunk takes at P threads what it took on one core), and the partition's extra work
beyond what the trace holds (it is in the trace: each P is recorded with its own partition).

Per case it prints and writes (DIR/scaling.md, DIR/scaling.json): the 1-thread step time, the
serial fraction s (the time in which only one thread works, at P, over the 1-thread step time),
Amdahl's bound 1 / (s + (1 - s) / P), the barriers and hand-overs per step, the predicted
speed-up at each P and where the predicted step time goes (serial, work / P, imbalance: the
scheduled parallel sections beyond work / P with free synchronisation, synchronisation: the
rest), per case and per stage. Where the 16-core reference (REFERENCE_16C, ms per step measured
on a 16-core VM) has the case, the recorded times are first scaled so that the 1-thread step
takes the reference's time (the model's costs are absolute, in microseconds, so the work must be
on the target's scale), and the measured speed-ups and the prediction's error are shown. --fit
first chooses the claim and barrier costs (a grid) that best match the reference on the given
cases, and predicts every case with them.

Exit status: 0 done, 1 a recording failed, 2 bad arguments or a malformed trace.
"""

import argparse
import datetime
import heapq
import json
import math
import os
import subprocess
import sys

STAGES = ["broad_phase", "narrow_phase", "persistence", "solve", "integrate", "outside"]

# ms per step, quadrant_bench release, medians of 3, Intel Xeon VM with 16 cores, at 1 / 2 / 4 /
# 8 / 16 threads. circle_stress 16000's 1-thread time varied from 1.21 to 1.74 ms: its range is
# kept, and the middle used. The circles' collapse at 8-16 threads is the pool running alone after
# misfiring load checks (oneTBB: 5.53 / 2.92 / 2.58 / 1.79 ms at 1 / 4 / 8 / 16 on 64000).
REFERENCE_16C = {
    ("pyramid", 5050): {1: 2.72, 2: 1.99, 4: 1.49, 8: 1.37, 16: 1.30},
    ("many_pyramids", 22000): {1: 19.2, 2: 12.0, 4: 7.20, 8: 5.63, 16: 3.73},
    ("circle_stress", 16000): {1: (1.21, 1.74), 2: 0.89, 4: 0.64, 8: 0.87, 16: 1.24},
    ("circle_stress", 64000): {1: 6.85, 2: 3.39, 4: 2.64, 8: 4.64, 16: 6.43},
    ("polygon_stress", 16000): {1: 2.53, 2: 1.42, 4: 1.35, 8: 1.06, 16: 0.88},
    ("polygon_stress", 64000): {1: 12.5, 2: 7.41, 4: 4.89, 8: 3.38, 16: 2.33},
}
# Steps recorded per case where --steps is not given: the big many_pyramids step takes tens of
# milliseconds on one core, times 5 thread counts and 3 repeats.
# The reference's cells that are the pool's misfire, not the step's structure: the model has no
# pool judgement, so they are shown but neither counted in the fit nor read as the model's error.
MISFIRES = {("circle_stress", 16000): {8, 16}, ("circle_stress", 64000): {8, 16}}
# The same VM with oneTBB as the task system (-DQUADRANT_TBB=ON: the same partition, no judgement
# of the machine), ms per step at 1 / 4 / 8 / 16 threads.
REFERENCE_16C_TBB = {("circle_stress", 64000): {1: 5.53, 4: 2.92, 8: 2.58, 16: 1.79}}
DEFAULT_STEPS = {}


class TraceError(Exception):
    """A malformed trace or bad arguments: exit status 2."""


class Params:
    """The model's costs, in microseconds (see the module's docstring). The defaults are the 2-core
    VMs' figures (docs/notes/thread_pool.md): a region's stage took 0.40-0.53 us beyond half its
    work at 2 threads, a parallel-for of trivial work 0.89 us, a sleeping worker about 100 us to
    wake; the pool spins 1 ms. A 16-core machine's are not measured here (--fit estimates them)."""

    def __init__(self, handover=0.5, barrier=0.5, claim=0.1, wake=100.0, wake_call=2.0, spin=1000.0):
        self.handover, self.barrier, self.claim = handover, barrier, claim
        self.wake, self.wake_call, self.spin = wake, wake_call, spin

    @staticmethod
    def free():
        """No synchronisation cost at all: list scheduling of the chunks alone."""
        return Params(0.0, 0.0, 0.0, 0.0, 0.0, math.inf)

    def as_dict(self):
        return {"handover_us": self.handover, "barrier_us": self.barrier, "claim_us": self.claim,
                "wake_us": self.wake, "wake_call_us": self.wake_call, "spin_us": self.spin}


class Pool:
    """P threads on one timeline: the caller (0) and workers 1..P-1. `now` is the caller's time;
    idle[w] is when worker w last stopped working (it spins until idle[w] + spin, then sleeps)."""

    def __init__(self, threads, params):
        self.p = threads
        self.prm = params
        self.now = 0.0
        self.idle = [0.0] * threads

    def serial(self, us):
        self.now += us

    def job(self, stages, runs):
        """Runs one parallel section (a list of stages, each a list of chunk times) and returns
        its duration on the caller and the barriers it waited at."""
        prm, p = self.prm, self.p
        start = self.now
        asleep = [w for w in range(1, p) if start - self.idle[w] > prm.spin]
        t0 = start + (prm.wake_call if asleep else 0.0)
        ready = [t0] + [t0 + (prm.wake if w in asleep else prm.handover) for w in range(1, p)]
        share = 2 * p
        claim_free = t0
        barriers = 0
        end = t0
        for chunks in stages:
            n = len(chunks)
            if n == 0:
                continue  # a stage of no items: the pool skips it
            front, back = 0, n
            done = list(ready)
            heap = [(ready[w], w) for w in range(p)]
            heapq.heapify(heap)
            stage_end = max(ready[0], t0)
            while front < back:
                t, w = heapq.heappop(heap)
                grant = max(t, claim_free)
                claim_free = grant + prm.claim
                take = max(1, -(-(back - front) // share)) if runs else 1
                if w % 2 == 0:  # the caller and even workers: from the front
                    work = sum(chunks[front:front + take])
                    front += take
                else:
                    work = sum(chunks[back - take:back])
                    back -= take
                finish = grant + prm.claim + work
                done[w] = finish
                stage_end = max(stage_end, finish)
                heapq.heappush(heap, (finish, w))
            barriers += 1
            nxt = stage_end + prm.barrier
            for w in range(p):
                if done[w] > nxt:  # still on its way (a worker waking up): it joins when there
                    ready[w] = done[w]
                elif nxt - done[w] > prm.spin:  # it fell asleep waiting (the caller too)
                    ready[w] = nxt + prm.wake
                else:
                    ready[w] = nxt
            end = ready[0]  # after the last stage: when the caller sees the job done
        for w in range(1, p):
            self.idle[w] = ready[w]
        self.now = max(end, start)
        return self.now - start, barriers


def check_trace(trace, path):
    for key in ("scene", "count", "traces"):
        if key not in trace:
            raise TraceError(f"{path}: no '{key}' (not a quadrant_scaling_trace recording?)")
    threads = [t["threads"] for t in trace["traces"]]
    if 1 not in threads:
        raise TraceError(f"{path}: no 1-thread trace (the speed-ups are against it)")
    for t in trace["traces"]:
        for step in t["steps"]:
            for s in step["sections"]:
                if s.get("kind") not in ("serial", "gap", "for", "region"):
                    raise TraceError(f"{path}: unknown section kind {s.get('kind')!r}")


def model_steps(steps, threads, params, scale=1.0):
    """Replays the steps on `threads` workers. Returns the totals over the steps (us): time, time
    per stage, serial (sections and gaps), work in parallel sections, barriers, hand-overs."""
    pool = Pool(threads, params)
    out = {"us": 0.0, "stage_us": {s: 0.0 for s in STAGES}, "serial_us": 0.0,
           "stage_serial_us": {s: 0.0 for s in STAGES}, "work_us": 0.0, "parallel_us": 0.0,
           "barriers": 0, "handovers": 0, "stage_barriers": {s: 0 for s in STAGES}}
    for step in steps:
        for s in step["sections"]:
            kind = s["kind"]
            stage = s.get("stage", "outside") if kind != "gap" else "outside"
            if kind in ("serial", "gap"):
                us = s["us"] * scale
                pool.serial(us)
                out["serial_us"] += us
                out["stage_serial_us"][stage] += us
                out["stage_us"][stage] += us
                out["us"] += us
                continue
            stages = [[c * scale for c in chunks] for chunks in s["us"]]
            if threads == 1:  # no job at all: the chunks one after another
                us = sum(sum(c) for c in stages)
                pool.serial(us)
                barriers = 0
            else:
                us, barriers = pool.job(stages, kind == "region" and s.get("runs", False))
                out["handovers"] += 1
            out["work_us"] += sum(sum(c) for c in stages)
            out["parallel_us"] += us
            out["barriers"] += barriers
            out["stage_barriers"][stage] += barriers
            out["stage_us"][stage] += us
            out["us"] += us
    return out


def one_thread_us(trace):
    """The 1-thread trace's total and per-stage time (us, summed over its steps)."""
    t1 = next(t for t in trace["traces"] if t["threads"] == 1)
    total = sum(step["us"] for step in t1["steps"])
    return total, model_steps(t1["steps"], 1, Params.free())


def shown_path(path):
    """A path as a report shows it: inside the checkout, relative to its root."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    full = os.path.abspath(path)
    return os.path.relpath(full, root) if full.startswith(root + os.sep) else path


def reference_from_json(path):
    """A measured reference from a quadrant_bench Google Benchmark JSON (a 16-core run committed
    under results/<machine>/bench.json): per (scene, count), the default engine's (`quadrant`)
    median ms per step at each thread count; the cases measured at one thread."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, ValueError) as e:
        raise TraceError(f"--reference {path}: {e}")
    if not isinstance(data, dict) or not isinstance(data.get("benchmarks"), list):
        raise TraceError(f"--reference {path}: not a Google Benchmark JSON (no 'benchmarks' list)")
    cells = {}
    for row in data["benchmarks"]:
        if not isinstance(row, dict) or row.get("run_type", "iteration") != "iteration":
            continue
        parts = str(row.get("run_name", row.get("name", ""))).split("/")
        fields = dict(p.split(":", 1) for p in parts[2:] if ":" in p)
        if len(parts) < 4 or parts[1] != "quadrant" or "n" not in fields or "threads" not in fields:
            continue
        ms = row.get("ms_per_step")
        if not isinstance(ms, (int, float)) or not ms > 0:
            continue
        cells.setdefault((parts[0], int(fields["n"])), {}).setdefault(int(fields["threads"]), []).append(float(ms))
    table = {case: {p: sorted(v)[len(v) // 2] if len(v) % 2 else (sorted(v)[len(v) // 2 - 1] + sorted(v)[len(v) // 2]) / 2
                    for p, v in by_p.items()}
             for case, by_p in cells.items() if 1 in by_p}
    if not table:
        raise TraceError(f"--reference {path}: no 'quadrant' rows measured at 1 thread")
    context = data.get("context") if isinstance(data.get("context"), dict) else {}
    about = (f"The measured reference is {shown_path(path)} (machine {context.get('machine', 'unknown')}, commit "
             f"{context.get('commit', 'unknown')}): the default engine's medians.")
    return table, about


def reference_of(scene, count, table=None):
    ref = (REFERENCE_16C if table is None else table).get((scene, count))
    if ref is None:
        return None
    one = ref[1]
    return {"one_ms": (one[0] + one[1]) / 2 if isinstance(one, tuple) else one,
            "one_range": one if isinstance(one, tuple) else None,
            "ms": {p: v for p, v in ref.items() if p != 1}}


class Case:
    """One recorded case ready to model: its steps per thread count, its 1-thread time and the
    scale that puts it on the reference's time (1 without a reference)."""

    def __init__(self, trace, use_reference=True, table=None):
        self.scene, self.count = trace["scene"], trace["count"]
        self.bodies = trace.get("bodies")
        self.warmup, self.repeats = trace.get("warmup"), trace.get("repeats")
        self.reduce = trace.get("reduce", "median")
        self.ref = reference_of(self.scene, self.count, table) if use_reference else None
        # The misfire cells are the table's (5cbc117); a measured JSON has none marked.
        self.misfires = MISFIRES.get((self.scene, self.count), ()) if table is None else ()
        self.recorded_total, self.t1_model = one_thread_us(trace)
        self.by_p = {t["threads"]: t["steps"] for t in trace["traces"]}
        self.nsteps = len(self.by_p[1])
        # The 1-thread step as its sections add up (gaps included: the trace's step time).
        self.t1_us = self.t1_model["us"]
        self.scale = self.ref["one_ms"] * 1000.0 * self.nsteps / self.t1_us if self.ref else 1.0
        self.t1_scaled = self.t1_us * self.scale

    def steps(self, p):
        if p not in self.by_p:
            raise TraceError(f"{self.scene} {self.count}: no trace at {p} threads (record it: --threads)")
        if len(self.by_p[p]) != self.nsteps:
            raise TraceError(f"{self.scene} {self.count}: {len(self.by_p[p])} steps at {p} threads, "
                             f"{self.nsteps} at 1")
        return self.by_p[p]

    def speedup(self, p, params):
        return self.t1_scaled / model_steps(self.steps(p), p, params, self.scale)["us"]

    def measured_speedup(self, p):
        """The reference's speed-up at p, or None (no reference, or a misfire cell)."""
        if not self.ref or p not in self.ref["ms"] or p in self.misfires:
            return None
        return self.ref["one_ms"] / self.ref["ms"][p]


def model_case(case, threads, params):
    """The model's answer for one case (a dict, written to scaling.json)."""
    n = case.nsteps
    ms = lambda us: us / n / 1000.0  # noqa: E731  (us summed over the steps -> ms per step)
    out = {"scene": case.scene, "count": case.count, "bodies": case.bodies, "steps": n,
           "warmup": case.warmup, "repeats": case.repeats, "reduce": case.reduce,
           "recorded_one_thread_ms": ms(case.recorded_total), "scale": case.scale,
           "one_thread_ms": ms(case.t1_scaled),
           "one_thread_stage_ms": {s: ms(case.t1_model["stage_us"][s] * case.scale) for s in STAGES},
           "reference": case.ref, "threads": {}}
    tbb = REFERENCE_16C_TBB.get((case.scene, case.count))
    for p in threads:
        steps = case.steps(p)
        full = model_steps(steps, p, params, case.scale)
        free = model_steps(steps, p, Params.free(), case.scale)
        s = full["serial_us"] / case.t1_scaled
        row = {
            "predicted_ms": ms(full["us"]),
            "speedup": case.t1_scaled / full["us"],
            "serial_fraction": s,
            "amdahl": 1.0 / (s + (1.0 - s) / p),
            "barriers": full["barriers"] / n,
            "handovers": full["handovers"] / n,
            "serial_ms": ms(full["serial_us"]),
            "work_ms": ms(full["work_us"]),
            "work_over_p_ms": ms(full["work_us"] / p),
            "imbalance_ms": ms(free["parallel_us"] - free["work_us"] / p),
            "sync_ms": ms(full["parallel_us"] - free["parallel_us"]),
            "stages": {},
        }
        for st in STAGES:
            one = case.t1_model["stage_us"][st] * case.scale
            if one <= 0 and full["stage_us"][st] <= 0:
                continue
            row["stages"][st] = {
                "predicted_ms": ms(full["stage_us"][st]),
                "speedup": one / full["stage_us"][st] if full["stage_us"][st] > 0 else None,
                "serial_ms": ms(full["stage_serial_us"][st]),
                "barriers": full["stage_barriers"][st] / n,
            }
        ref = case.ref
        if ref and p in ref["ms"]:
            measured = ref["one_ms"] / ref["ms"][p]
            row["measured_ms"] = ref["ms"][p]
            row["measured_speedup"] = measured
            row["error_pct"] = 100.0 * (row["speedup"] - measured) / measured
            row["misfire"] = case.measured_speedup(p) is None
            if ref["one_range"]:
                row["measured_speedup_range"] = [ref["one_range"][0] / ref["ms"][p], ref["one_range"][1] / ref["ms"][p]]
        if tbb and p in tbb:
            row["tbb_measured_speedup"] = tbb[1] / tbb[p]
        out["threads"][str(p)] = row
    return out


# The fit's grid (us): the claim word's hold per claim and the barrier.
FIT_CLAIMS = [0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.6]
FIT_BARRIERS = [0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0]


def fit(cases, threads, base):
    """The claim and barrier costs (a grid) that best match the reference's speed-ups of `cases`
    at `threads` (least squares of the log ratio; misfire cells left out). Returns (params, rms of
    the log ratio, cells)."""
    cells = [(c, p, c.measured_speedup(p)) for c in cases for p in threads if c.measured_speedup(p)]
    if not cells:
        raise TraceError("--fit: the reference has none of these cases at these thread counts")
    best = None
    for claim in FIT_CLAIMS:
        for barrier in FIT_BARRIERS:
            prm = Params(base.handover, barrier, claim, base.wake, base.wake_call, base.spin)
            err = sum(math.log(c.speedup(p, prm) / m) ** 2 for c, p, m in cells)
            rms = math.sqrt(err / len(cells))
            if best is None or rms < best[1]:
                best = (prm, rms)
    return best[0], best[1], len(cells)


def fmt(x, digits=2):
    return "-" if x is None else f"{x:.{digits}f}"


def report(cases, params, threads, note=""):
    """The markdown report."""
    lines = ["# Scaling model: predicted speed-ups", ""]
    lines.append("Each case's steps were recorded on one core in the partition of every thread count "
                 "(benchmarks/scaling_trace.cpp) and replayed on P workers with the pool's claiming "
                 "rules (tools/scaling.py's docstring has the model). Costs: " +
                 ", ".join(f"{k} {v:g}" for k, v in params.as_dict().items()) + ".")
    machine, commit = os.environ.get("QUADRANT_MACHINE"), os.environ.get("QUADRANT_COMMIT")
    if machine or commit:
        lines += ["", f"Recorded on {machine or 'an unnamed machine'}, commit {commit or 'unknown'}; per case "
                  + ", ".join(f"{c['scene']} {c['count']}: {c['steps']} steps after {c['warmup']}, "
                              f"{c['reduce']} of {c['repeats']} repeats" for c in cases) + "."]
    if note:
        lines += ["", note]
    lines += ["", "Speed-up against 1 thread; s: the serial fraction (time in which one thread works, at "
              "16 threads or the largest P, over the 1-thread step); Amdahl: 1 / (s + (1 - s) / P) at that P; "
              "barriers and hand-overs per step at that P. Measured: the 16-core reference "
              "(quadrant_bench, ms per step, medians of 3), where it has the case; error: predicted "
              "against measured speed-up.", ""]
    top = max(threads)
    head = "| case | 1 thread ms | s | Amdahl | barriers | hand-overs | " + " | ".join(
        f"{p} thr predicted / measured (error)" for p in threads) + " |"
    lines += [head, "|" + "---|" * (6 + len(threads))]
    for c in cases:
        r = c["threads"][str(top)]
        cells = []
        for p in threads:
            row = c["threads"][str(p)]
            if "measured_speedup" in row:
                m = row["measured_speedup"]
                ms = (f"{row['measured_speedup_range'][0]:.2f}-{row['measured_speedup_range'][1]:.2f}"
                      if "measured_speedup_range" in row else f"{m:.2f}")
                err = "misfire" if row.get("misfire") else f"{row['error_pct']:+.0f} %"
                cells.append(f"{row['speedup']:.2f} / {ms} ({err})")
            else:
                cells.append(f"{row['speedup']:.2f}")
        one = f"{c['one_thread_ms']:.3g}"
        if c["scale"] != 1.0:
            one += f" (here {c['recorded_one_thread_ms']:.3g})"
        lines.append(f"| {c['scene']} {c['count']} | {one} | {100 * r['serial_fraction']:.0f} % | "
                     f"{r['amdahl']:.2f} | {r['barriers']:.0f} | {r['handovers']:.0f} | " + " | ".join(cells) + " |")
    tbb = [c for c in cases if any("tbb_measured_speedup" in r for r in c["threads"].values())]
    if any(r.get("misfire") for c in cases for r in c["threads"].values()):
        lines += ["", "misfire: the reference's cell is the pool running alone after misfiring load checks "
                  "(not in the model); oneTBB on the same VM (same partition, no such judgement), "
                  "speed-up predicted / measured:", ""]
        for c in tbb:
            lines.append(f"- {c['scene']} {c['count']}: " + ", ".join(
                f"{p} threads {r['speedup']:.2f} / {r['tbb_measured_speedup']:.2f} "
                f"({100 * (r['speedup'] / r['tbb_measured_speedup'] - 1):+.0f} %)"
                for p, r in c["threads"].items() if "tbb_measured_speedup" in r))
    lines += ["", "## Where the predicted step goes", "",
              "ms per step (on the reference's scale where it has the case): serial (sections and the "
              "code between them, one thread), work / P (the parallel sections' work shared evenly), "
              "imbalance (the parallel sections scheduled with free synchronisation, beyond work / P: "
              "short stages, large chunks), synchronisation (hand-overs, claims, barriers, wake-ups).", "",
              "| case | P | predicted ms | measured ms | serial | work / P | imbalance | synchronisation | barriers | hand-overs |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for c in cases:
        for p in threads:
            r = c["threads"][str(p)]
            lines.append(f"| {c['scene']} {c['count']} | {p} | {r['predicted_ms']:.3f} | "
                         f"{fmt(r.get('measured_ms'), 3)} | {r['serial_ms']:.3f} | {r['work_over_p_ms']:.3f} | "
                         f"{r['imbalance_ms']:.3f} | {r['sync_ms']:.3f} | {r['barriers']:.0f} | {r['handovers']:.0f} |")
    lines += ["", "## Per stage", "",
              "Per stage: the 1-thread ms, and at each P the predicted speed-up; at "
              f"{top} threads the serial ms, the stage's serial fraction s (over its 1-thread time), "
              "Amdahl's bound and the barriers per step. 'outside': the step's code between the stage "
              "runner's sections (serial). At one thread the code of a lone part (StageRunner::Beside) "
              "between its own sections is 'outside'; at P threads it is inside the lone part's chunk, "
              "in its stage: that stage's speed-up reads a little low and outside's high.", "",
              "| case | stage | 1 thread ms | " + " | ".join(f"{p} thr" for p in threads) +
              f" | serial ms at {top} | s | Amdahl at {top} | barriers at {top} |",
              "|" + "---|" * (7 + len(threads))]
    for c in cases:
        for st in STAGES:
            one = c["one_thread_stage_ms"][st]
            rows = [c["threads"][str(p)]["stages"].get(st) for p in threads]
            if one <= 0 and not any(rows):
                continue
            last = c["threads"][str(top)]["stages"].get(st) or {}
            frac = last.get("serial_ms", 0.0) / one if one > 0 else None
            amdahl = 1.0 / (frac + (1.0 - frac) / top) if frac is not None and frac < 1 else None
            lines.append(f"| {c['scene']} {c['count']} | {st} | {one:.3f} | " +
                         " | ".join(fmt(r["speedup"] if r else None) for r in rows) +
                         f" | {fmt(last.get('serial_ms'), 3)} | "
                         f"{'-' if frac is None else f'{100 * frac:.0f} %'} | {fmt(amdahl)} | "
                         f"{fmt(last.get('barriers'), 0)} |")
    lines.append("")
    return "\n".join(lines)


def parse_list(text, what, most=64):
    problem = f"{what}: '{text}' is not a comma-separated list of integers in [1, {most}]"
    try:
        items = [int(x) for x in text.split(",")]
    except ValueError:
        raise TraceError(problem)
    if not items or any(p < 1 or p > most for p in items):
        raise TraceError(problem)
    return items


def cases_of(scenes, counts):
    """(scene, count) pairs: every scene at every count, or where no counts are given each scene at
    its reference counts (all the reference's cases where no scenes are given either)."""
    if scenes is None and counts is None:
        return list(REFERENCE_16C)
    scenes = scenes.split(",") if scenes else list(dict.fromkeys(s for s, _ in REFERENCE_16C))
    if counts is not None:
        counts = parse_list(counts, "--counts", 10000000)
        return [(s, c) for s in scenes for c in counts]
    cases = []
    for scene in scenes:
        mine = [c for s, c in REFERENCE_16C if s == scene]
        if not mine:
            raise TraceError(f"--scenes: {scene} has no reference count; give --counts")
        cases += [(scene, c) for c in mine]
    return cases


def record(binary, scene, count, threads, steps, warmup, repeats, path):
    cmd = [binary, "--scene", scene, "--count", str(count), "--threads", ",".join(str(p) for p in [1] + threads),
           "--steps", str(steps), "--warmup", str(warmup), "--repeats", str(repeats), "--out", path]
    print("scaling: recording " + " ".join(cmd[1:]), file=sys.stderr, flush=True)
    return subprocess.run(cmd, check=False).returncode


def main(argv=None):
    ap = argparse.ArgumentParser(description="The scaling model (tools/scaling.py's docstring).")
    ap.add_argument("--trace", action="append", default=[], help="a recording (quadrant_scaling_trace's JSON)")
    ap.add_argument("--record", metavar="BINARY", help="record --cases with this quadrant_scaling_trace first")
    ap.add_argument("--scenes", help="scenes to record (default: the reference's)")
    ap.add_argument("--counts", help="body counts, for every scene (default: each scene's reference counts)")
    ap.add_argument("--steps", type=int, help="recorded steps per case (default 120, the bench's timed steps)")
    ap.add_argument("--warmup", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", default="2,4,8,16")
    ap.add_argument("--out", help="directory for scaling.md and scaling.json (and the recordings)")
    ap.add_argument("--handover-us", type=float, default=Params().handover,
                    help="a spinning worker's start on a new job (default %(default)s)")
    ap.add_argument("--barrier-us", type=float, default=Params().barrier,
                    help="from a stage's last chunk to every thread's next claim (default %(default)s)")
    ap.add_argument("--claim-us", type=float, default=Params().claim,
                    help="the claim word's hold per claim; claims queue on it (default %(default)s)")
    ap.add_argument("--wake-us", type=float, default=Params().wake,
                    help="a sleeping thread's wake-up (default %(default)s)")
    ap.add_argument("--wake-call-us", type=float, default=Params().wake_call,
                    help="the caller's futex wake when a worker sleeps (default %(default)s)")
    ap.add_argument("--spin-us", type=float, default=Params().spin,
                    help="how long a waiting thread spins before it sleeps (default %(default)s)")
    ap.add_argument("--reference", default="16c", metavar="16c|none|JSON",
                    help="scale to and compare with a 16-core reference where it has the case: 16c, the "
                         "issue's table (5cbc117); JSON, a measured quadrant_bench run such as "
                         "results/intel-xeon-16c/bench.json (its default engine's medians); none")
    ap.add_argument("--fit", metavar="SCENE:COUNT,...",
                    help="first fit --claim-us and --barrier-us (a grid) to the reference's speed-ups of "
                         "these cases (recorded or given with --trace), then model every case with them")
    args = ap.parse_args(argv)
    try:
        threads = parse_list(args.threads, "--threads")
        for name in ("handover_us", "barrier_us", "claim_us", "wake_us", "wake_call_us", "spin_us"):
            v = getattr(args, name)
            if not (v >= 0) or math.isnan(v):
                raise TraceError(f"--{name.replace('_', '-')}: {v} is not a number >= 0")
        reference_table, about = (None, "") if args.reference in ("16c", "none") else reference_from_json(args.reference)
        params = Params(args.handover_us, args.barrier_us, args.claim_us, args.wake_us, args.wake_call_us, args.spin_us)
        paths = list(args.trace)
        if args.record:
            if not args.out:
                raise TraceError("--record needs --out (the recordings go there)")
            os.makedirs(args.out, exist_ok=True)
            for scene, count in cases_of(args.scenes, args.counts):
                path = os.path.join(args.out, f"trace_{scene}_{count}.json")
                steps = args.steps or DEFAULT_STEPS.get(scene, 120)
                status = record(args.record, scene, count, threads, steps, args.warmup, args.repeats, path)
                if status == 2:
                    return 2
                if status != 0:
                    print(f"scaling: recording {scene} {count} failed (exit {status})", file=sys.stderr)
                    return 1
                paths.append(path)
        if not paths:
            raise TraceError("nothing to model: give --trace FILE or --record BINARY")
        cases = []
        for path in paths:
            try:
                with open(path, encoding="utf-8") as f:
                    trace = json.load(f)
            except (OSError, ValueError) as e:
                raise TraceError(f"{path}: {e}")
            check_trace(trace, path)
            cases.append(Case(trace, args.reference != "none", reference_table))
        note = about
        if args.fit:
            wanted = set()
            for item in args.fit.split(","):
                scene, _, count = item.partition(":")
                if not scene or not count.isdigit():
                    raise TraceError(f"--fit: '{item}' is not SCENE:COUNT")
                wanted.add((scene, int(count)))
            chosen = [c for c in cases if (c.scene, c.count) in wanted]
            if len(chosen) != len(wanted):
                raise TraceError(f"--fit: {args.fit}: not every case was recorded or given")
            params, rms, cells = fit(chosen, threads, params)
            note = (about + " " if about else "") + (f"Claim and barrier costs fitted to the reference's speed-ups of {args.fit} ({cells} cells, "
                    f"grid claim {FIT_CLAIMS} us x barrier {FIT_BARRIERS} us; rms of the log ratio "
                    f"{rms:.3f}); every other case is predicted with them.")
            print(f"scaling: fitted claim {params.claim:g} us, barrier {params.barrier:g} us (rms log ratio {rms:.3f})",
                  file=sys.stderr)
        results = [model_case(c, threads, params) for c in cases]
    except TraceError as e:
        print(f"scaling: {e}", file=sys.stderr)
        return 2
    cases = results
    text = report(cases, params, threads, note)
    print(text)
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "scaling.md"), "w", encoding="utf-8") as f:
            f.write(text)
        # Where and when the recordings were modelled (results/README.md reads date and commit).
        context = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
                   "machine": os.environ.get("QUADRANT_MACHINE"), "commit": os.environ.get("QUADRANT_COMMIT"),
                   "reference": shown_path(args.reference) if os.path.exists(args.reference) else args.reference}
        with open(os.path.join(args.out, "scaling.json"), "w", encoding="utf-8") as f:
            json.dump({"context": context, "params": params.as_dict(), "fit": args.fit, "threads": threads,
                       "cases": cases}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
