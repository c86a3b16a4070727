#!/usr/bin/python3
"""The suite's ETA (benchmarks/eta.h, issue #29 item 3) on recorded runs: every run of a committed
bench.json (scene, engine, N, threads, steps, warm-up and its time, real_time x iterations) is
replayed through the model by eta_replay (tests/tools/eta_replay.cpp), in the file's order and in
shuffled orders like the suite's random interleaving; from the tenth run on, every ETA must be
within a factor of 1.5 of the time the remaining runs took. Prints the worst error of each
replay.

usage: /usr/bin/python3 eta_test.py ETA_REPLAY ROOT     (registered with ctest as eta_replay)
"""

import os
import random
import subprocess
import sys

REPLAY, ROOT = sys.argv[1], os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(ROOT, "tools"))
import gbench_json  # noqa: E402

FROM_RUN = 10
LIMIT = 1.5
SHUFFLES = 20
RECORDED = ["results/amd-epyc-2c/bench.json", "results/intel-xeon-2c/bench.json"]


def recorded_runs(path):
    """[(scene, engine, n, threads, steps, warmup, seconds)] of the file's repetitions, in file order."""
    data = gbench_json.load(path)
    ctx = data.get("context", {})
    runs = []
    for row in data["benchmarks"]:
        if row.get("run_type") != "iteration" or row.get("error_occurred"):
            continue
        parsed = gbench_json.parse_quadrant_name(row.get("run_name") or row["name"])
        if not parsed:
            continue
        unit = gbench_json.TIME_UNITS_S[row.get("time_unit", "ns")]
        seconds = row["real_time"] * unit * row.get("iterations", 1)
        steps = int(row.get("steps", ctx.get("steps", 0)))
        warmup = int(row.get("warmup", ctx.get("warmup", 0)))
        runs.append((*parsed, steps, warmup, seconds))
    return runs


def worst_ratio(etas, remaining):
    """(worst max(ETA/actual, actual/ETA) from run FROM_RUN to the last but one, that run)."""
    worst, where = 1.0, None
    for i in range(FROM_RUN - 1, len(etas) - 1):
        actual, eta = remaining[i], etas[i]
        ratio = max(eta / actual, actual / eta) if actual > 0 and eta > 0 else float("inf")
        if ratio > worst:
            worst, where = ratio, i + 1
    return worst, where


def replay(runs):
    """(worst ratio from FROM_RUN on, the run where it was, ETA at run FROM_RUN / actual, the
    old ETA's worst ratio: elapsed / runs done x runs left)."""
    text = "".join(f"{s} {e} {n} {t} {st} {w} {sec:.9f}\n" for s, e, n, t, st, w, sec in runs)
    out = subprocess.run([REPLAY], input=text, capture_output=True, text=True, check=True).stdout
    etas = [float(line.split()[1]) for line in out.splitlines()]
    assert len(etas) == len(runs), (len(etas), len(runs))
    remaining = [0.0] * len(runs)
    left = 0.0
    for i in range(len(runs) - 1, -1, -1):
        remaining[i] = left  # after run i + 1 is done
        left += runs[i][-1]
    worst, where = worst_ratio(etas, remaining)
    elapsed, old = 0.0, []
    for i, run in enumerate(runs):
        elapsed += run[-1]
        old.append(elapsed / (i + 1) * (len(runs) - i - 1))
    return worst, where, etas[FROM_RUN - 1] / remaining[FROM_RUN - 1], worst_ratio(old, remaining)[0]


def main():
    failures = 0
    for rel in RECORDED:
        path = os.path.join(ROOT, rel)
        runs = recorded_runs(path)
        total = sum(r[-1] for r in runs)
        orders = [("file order", runs)]
        rng = random.Random(29)
        for k in range(SHUFFLES):
            shuffled = list(runs)
            rng.shuffle(shuffled)
            orders.append((f"shuffle {k + 1}", shuffled))
        worst_all = old_all = 1.0
        for label, order in orders:
            worst, where, at10, old = replay(order)
            worst_all = max(worst_all, worst)
            old_all = max(old_all, old)
            ok = worst <= LIMIT
            failures += not ok
            if not ok or label in ("file order", "shuffle 1"):
                print(f"{'ok' if ok else 'FAIL'}: {rel} ({len(runs)} runs, {total:.0f} s), {label}: "
                      f"ETA/actual at run {FROM_RUN} = {at10:.2f}; worst error from run {FROM_RUN} on "
                      f"{worst:.2f}x (run {where}); the old ETA's {old:.2f}x")
        print(f"{rel}: worst error over the file order and {SHUFFLES} shuffles: {worst_all:.2f}x "
              f"(limit {LIMIT}x; the old ETA, elapsed / runs done x runs left: {old_all:.2f}x)")
    if failures:
        print(f"{failures} replay(s) with an ETA off by more than {LIMIT}x from run {FROM_RUN} on")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
