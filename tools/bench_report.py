#!/usr/bin/python3
"""Turn a quadrant_bench Google Benchmark JSON into speed-up tables and FPS plots.

Usage (run with Debian's interpreter, /usr/bin/python3, which sees python3-matplotlib):

    /usr/bin/python3 tools/bench_report.py bench.json [--out DIR]
        writes DIR/speedup.md and DIR/fps_<scene>.png for every scene in the run and prints
        the Markdown to stdout (DIR defaults to the JSON's directory)
    /usr/bin/python3 tools/bench_report.py bench.json --busy bench_busy.json [--out DIR]
        the same, plus a busy machine table from a `tools/quadrant bench --busy K` run
    /usr/bin/python3 tools/bench_report.py --check bench.json
        validates the JSON's structure; exits 1 with a message naming the first problems

Noise: a figure whose repetitions spread by more than 50 %, or measured while other processes
used the machine (see flags()), is marked **noisy** in every table (speed-ups and Quadrant/peer
ratios included) and listed; speedup.md opens with how many there are (and with the run's own
flag, a load average above the cores before it), the plots ring them and their footers count
them: such figures are not results.

Figures: for every benchmark <scene>/<engine>/n:<N>/threads:<T> the MEDIAN steps per second
over its repetitions, computed here from the per-repetition rows (Google Benchmark's own
aggregate rows are ignored, except that a file holding only aggregates is read through its
_median rows). Partial data (engines, thread counts or sizes missing) gives partial tables,
never a crash.
"""

import argparse
import math
import os
import re
import statistics
import sys

import gbench_json  # the one reader of Google Benchmark JSON in tools/
import plot_style  # one colour and label per engine in every figure

LABEL_RE = re.compile(r"^[0-9a-f]{16}$")
SCENE_NOUNS = {"circle_stress": "circles", "polygon_stress": "polygons", "pyramid": "boxes",
               "many_pyramids": "boxes", "tumbler": "boxes"}
THESIS_FIGURES = {"circle_stress": "Figure 14", "polygon_stress": "Figure 15"}
ENGINE_TITLES = {
    "quadrant": "Quadrant",
    "box2d": "Box2D 2.4.1",
    "bullet": "Bullet 3.24 (2D)",
    "chipmunk": "Chipmunk 7",
}


def row_steps_per_second(row):
    """The row's steps per second, from the counter or else from real_time and steps."""
    v = row.get("steps_per_second")
    if isinstance(v, (int, float)) and v > 0:
        return float(v)
    steps, real = row.get("steps"), row.get("real_time")
    unit = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}.get(row.get("time_unit", "ns"))
    if isinstance(steps, (int, float)) and isinstance(real, (int, float)) and real > 0 and unit:
        return float(steps) / (real * unit)
    return None


# ---- --check ---------------------------------------------------------------------------------


def check(path):
    """Returns a list of problems (empty if the file is well formed): gbench_json's of the file's
    structure, then quadrant_bench's of every row."""
    try:
        data = gbench_json.read(path)
    except gbench_json.GBenchError as e:
        return [str(e)]
    problems, benches = gbench_json.structure_problems(data)
    if not isinstance(data, dict):
        return problems
    iterations = 0
    for i, row in enumerate(benches):
        if not isinstance(row, dict):
            problems.append(f"benchmarks[{i}] is not an object")
            continue
        name = row.get("name", "")
        if not gbench_json.parse_quadrant_name(name):
            problems.append(f"benchmarks[{i}]: name {name!r} does not match <scene>/<engine>/n:<int>/threads:<int>")
            continue
        if row.get("error_occurred"):
            problems.append(f"{name}: failed: {row.get('error_message', 'no message')}")
            continue
        aggregate = gbench_json.aggregate_of(row)
        if aggregate:
            if aggregate in ("mean", "median"):
                v = row.get("steps_per_second")
                if not (isinstance(v, (int, float)) and v > 0):
                    problems.append(f"{name}: steps_per_second {v!r} is not > 0")
            continue
        iterations += 1
        v = row.get("steps_per_second")
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            problems.append(f"{name}: steps_per_second {v!r} is not > 0")
        label = row.get("label")
        if not (isinstance(label, str) and LABEL_RE.match(label)):
            problems.append(f"{name}: label {label!r} is not a 16-hex-digit state hash")
    if benches and iterations == 0 and not any(
            isinstance(r, dict) and gbench_json.aggregate_of(r) == "median" for r in benches):
        problems.append("no per-repetition rows and no _median rows")
    return problems


# ---- Collecting ------------------------------------------------------------------------------


class Results:
    def __init__(self, data):
        """data: a Google Benchmark file as gbench_json.load returns it; its rows are read by
        gbench_json.Rows (per-repetition rows, _median aggregates, failures by base name) and
        keyed here by (scene, engine, n, threads)."""
        self.context = data.get("context", {}) if isinstance(data, dict) else {}
        rows = gbench_json.Rows(data)
        key_of = {name: gbench_json.parse_quadrant_name(name) for name in rows.order}
        reps = {key_of[name]: r for name, r in rows.reps.items() if key_of[name]}  # key -> list of rows
        medians = {key_of[name]: r for name, r in rows.medians.items() if key_of[name]}  # key -> median row
        self.failed = [(name, msg) for name, msg in rows.failed_rows if gbench_json.parse_quadrant_name(name)]
        self.stats = {}  # key -> dict
        for key in set(reps) | set(medians):
            rows_k = reps.get(key)
            if rows_k:
                sps = [v for v in (row_steps_per_second(r) for r in rows_k) if v]
                if not sps:
                    continue
                self.stats[key] = {
                    "sps": statistics.median(sps),
                    "min": min(sps),
                    "max": max(sps),
                    "reps": len(sps),
                    "contacts": statistics.median([r.get("contacts", 0) for r in rows_k]),
                    "memory_mb": statistics.median([r.get("memory_mb", 0) for r in rows_k]),
                    "labels": sorted({r.get("label", "") for r in rows_k}),
                    "bound": statistics.median([r["balance_bound"] for r in rows_k]) if all("balance_bound" in r for r in rows_k) else None,
                    "load_avg": max((r["load_avg"] for r in rows_k if isinstance(r.get("load_avg"), (int, float))), default=None),
                    "others_cpu": max((r["others_cpu"] for r in rows_k if isinstance(r.get("others_cpu"), (int, float))), default=None),
                }
            else:
                row = medians[key]
                v = row_steps_per_second(row)
                if not v:
                    continue
                self.stats[key] = {
                    "sps": v, "min": v, "max": v, "reps": row.get("repetitions", 1),
                    "contacts": row.get("contacts", 0), "memory_mb": row.get("memory_mb", 0),
                    "labels": [row.get("label", "")] if row.get("label") else [],
                    "bound": row.get("balance_bound"),
                }
        # Orders: as in the context where given, else as first seen; Quadrant first.
        seen_scenes, seen_engines = [], []
        for parsed in (key_of[name] for name in rows.order):
            if parsed:
                if parsed[0] not in seen_scenes:
                    seen_scenes.append(parsed[0])
                if parsed[1] not in seen_engines:
                    seen_engines.append(parsed[1])
        present_scenes = {k[0] for k in self.stats}
        present_engines = {k[1] for k in self.stats}
        self.scenes = [s for s in seen_scenes if s in present_scenes]
        engines = self._ctx_list("engines") or seen_engines
        engines = [e for e in engines if e in present_engines] + [e for e in seen_engines if e in present_engines and e not in engines]
        self.engines = sorted(engines, key=lambda e: (not e.startswith("quadrant"), engines.index(e)))
        self.threads = sorted({k[3] for k in self.stats})
        self.cores = self._cores()
        unsupported = self.context.get("unsupported", "")
        self.unsupported = [u for u in unsupported.split(";") if u.strip()] if isinstance(unsupported, str) else []
        errors = self.context.get("errors", "")
        self.errors = [u for u in errors.split(";") if u.strip()] if isinstance(errors, str) else []

    def _ctx_list(self, key):
        v = self.context.get(key)
        return [x for x in v.split(",") if x] if isinstance(v, str) else []

    def _cores(self):
        return gbench_json.context_cores(self.context)

    def beyond_engine(self, engine, threads):
        """True when the run's context says the engine uses fewer than `threads` threads."""
        try:
            return threads > int(self.context.get(f"engine_max_threads_{engine}"))
        except (TypeError, ValueError):
            return False

    def counts(self, scene):
        return sorted({k[2] for k in self.stats if k[0] == scene})

    def get(self, scene, engine, n, threads):
        return self.stats.get((scene, engine, n, threads))


# ---- Noise flags ------------------------------------------------------------------------------

# A benchmark's figure is flagged, not printed as a result, when its repetitions spread by more
# than this fraction of their median ((max - min) / median) ...
SPREAD_LIMIT = 0.5
# ... or when the machine was loaded beyond its cores by something other than the run: the
# 1-minute load average before the run started (context load_avg_before, read by tools/quadrant
# before it starts any busy process) above the core count, or other processes using more than
# OTHERS_LIMIT cores during a repetition beyond the run's own --busy processes (counter
# others_cpu, over each repetition's setup, warm-up and timed steps). The load average during
# the run is not the test: it counts the run's own threads, so every quiet 3- and 4-thread run
# on 2 cores would exceed the cores.
OTHERS_LIMIT = gbench_json.OTHERS_LIMIT  # the rule is gbench_json's, shared with compare.py


def busy_count(results):
    return gbench_json.busy_processes(results.context)


def run_flags(results):
    """Reasons (strings) that make the whole run suspect."""
    return gbench_json.run_load_problems(results.context)


def flags(results):
    """{key: [reasons]} for benchmarks whose figures are not to be trusted as results."""
    out = {}
    busy = busy_count(results)
    for key, s in results.stats.items():
        why = []
        if s["reps"] > 1 and s["sps"] > 0 and (s["max"] - s["min"]) / s["sps"] > SPREAD_LIMIT:
            why.append(f"repetitions spread {100 * (s['max'] - s['min']) / s['sps']:.0f} %")
        others = s.get("others_cpu")
        if others is not None and others - busy > OTHERS_LIMIT:
            why.append(f"other processes used {others:.1f} cores" + (f" ({busy} of them the run's busy loops)" if busy else ""))
        if why:
            out[key] = why
    return out


def flag_mark(flagged, key):
    return " (**noisy**)" if key in flagged else ""


def flag_lines(results, flagged, title):
    """Markdown lines listing the flagged runs of `results`."""
    lines = []
    whole = run_flags(results)
    if not whole and not flagged:
        return [f"No {title} figure is flagged: every benchmark's repetitions spread by at most "
                f"{100 * SPREAD_LIMIT:.0f} %, other processes used at most {OTHERS_LIMIT} cores beside "
                "the run, and the load average before it was within the core count.", ""]
    if whole:
        lines.append(f"**Every {title} figure is flagged**: " + "; ".join(whole) + ".")
        lines.append("")
    if flagged:
        lines.append(f"Flagged {title} figures (marked **noisy** in the tables; re-run them on a quiet machine):")
        lines.append("")
        for key in sorted(flagged):
            lines.append(f"- `{key[0]}/{key[1]}/n:{key[2]}/threads:{key[3]}`: " + "; ".join(flagged[key]))
        lines.append("")
    return lines


def busy_markdown(busy, quiet_cores):
    """The busy machine table: every engine, scene and size at each thread count."""
    lines = []
    out = lines.append
    k = busy_count(busy)
    flagged = flags(busy)
    cores = busy.cores or quiet_cores
    out(f"## Busy machine ({k} busy process{'es' if k != 1 else ''} beside the run)")
    out("")
    out(f"The same benchmarks while `tools/quadrant bench --busy {k}` ran {k} shell busy loop(s) for the "
        f"whole run (commit {ctx(busy, 'commit')}, {ctx(busy, 'date')}, {ctx(busy, 'steps')} timed steps "
        f"after {ctx(busy, 'warmup')} warm-up). A graceful engine is no slower on more threads than "
        "on one: 'vs 1T' is the steps-per-second ratio to 1 thread under the same load.")
    out("")
    threads = busy.threads or [1]
    head = ["scene", "N", "engine"] + [f"steps/s {t}T" for t in threads] + [f"vs 1T {t}T" for t in threads if t != 1]
    out("| " + " | ".join(head) + " |")
    out("|---|---:|---|" + "---:|" * (len(head) - 3))
    for scene in busy.scenes:
        for n in busy.counts(scene):
            for e in busy.engines:
                base = busy.get(scene, e, n, 1)
                cells = []
                anything = False
                for t in threads:
                    s = busy.get(scene, e, n, t)
                    anything |= s is not None
                    cells.append(fmt_sps(s["sps"]) + flag_mark(flagged, (scene, e, n, t)) if s else
                                 ("-" if busy.beyond_engine(e, t) else "n/a"))
                for t in threads:
                    if t == 1:
                        continue
                    s = busy.get(scene, e, n, t)
                    cells.append(f"{s['sps'] / base['sps']:.2f}x" if s and base else ("-" if busy.beyond_engine(e, t) else "n/a"))
                if anything:
                    out(f"| {scene} | {n} | {engine_title(e)} | " + " | ".join(cells) + " |")
    out("")
    if cores:
        out(f"Thread counts above {cores} are oversubscribed even without the busy loops.")
        out("")
    lines.extend(flag_lines(busy, flagged, "busy-machine"))
    return lines


# ---- Markdown --------------------------------------------------------------------------------


def fmt_sps(v):
    if v is None:
        return "n/a"
    if v >= 100:
        return f"{v:,.0f}"
    if v >= 10:
        return f"{v:.1f}"
    return f"{v:.2f}"


def engine_title(engine):
    base, _, variant = engine.partition(":")
    title = ENGINE_TITLES.get(base, engine)
    return f"{title} ({variant})" if variant else title


def ctx(results, key, default="unknown"):
    v = results.context.get(key)
    return default if v in (None, "") else v


# A speed-up this much above the measured bound cannot come from the partition: noise.
ABOVE_BOUND = 1.2


def speedup_cell(speedup, bound):
    """"1.22x (bound 1.83)", "4.00x (work on 1 thread; noise)": the speed-up and, where measured,
    the bound it is read against (see the reading guide above the tables)."""
    cell = f"{speedup:.2f}x"
    if not bound:
        return cell
    noise = speedup > bound * ABOVE_BOUND
    if bound < 1.05:
        return cell + (" (work on 1 thread; noise)" if noise else " (work on 1 thread)")
    return cell + f" (bound {bound:.2f}" + ("; noise)" if noise else ")")


def warning_lines(results, flagged, busy=None):
    """The report's first lines: what makes its figures unquotable, before any figure."""
    lines = []
    whole = run_flags(results)
    if busy_count(results):
        lines.append(f"> **Busy machine run**: {busy_count(results)} busy loop(s) ran beside every benchmark; "
                     "these figures measure a loaded machine on purpose.")
    if whole:
        lines.append(f"> **Warning: every figure below is flagged**: {'; '.join(whole)}. They are not "
                     "results: re-run on a quiet machine before quoting any of them.")
    if flagged:
        total = len(results.stats)
        lines.append(f"> **Warning: {len(flagged)} of {total} benchmark figures are noisy** (repetitions spread "
                     f"by more than {100 * SPREAD_LIMIT:.0f} %, or other processes used more than {OTHERS_LIMIT} "
                     "cores): marked (**noisy**) in every table, the speed-ups and ratios included, and listed "
                     "under 'Flagged' below.")
    if busy is not None:
        busy_flagged = flags(busy)
        if busy_flagged or run_flags(busy):
            lines.append(f"> **Warning: the busy-machine table has {len(busy_flagged)} noisy figure(s)**"
                         + (f" and {'; '.join(run_flags(busy))}" if run_flags(busy) else "") + ".")
    # One paragraph each (consecutive '>' lines would run together).
    return [part for line in lines for part in (line, "")]


def markdown(results, source, busy=None):
    c = results.context
    flagged = flags(results)
    whole = run_flags(results)
    cores = results.cores
    lines = []
    out = lines.append
    out("# Steps per second and thread speed-up")
    out("")
    for line in warning_lines(results, flagged, busy):
        out(line)
    out(f"- machine: {ctx(results, 'machine', ctx(results, 'host_name'))}")
    out(f"- CPU: {ctx(results, 'cpu_model')}, cores: {cores if cores else 'unknown'}")
    out(f"- compiler: {ctx(results, 'compiler')}; build type {ctx(results, 'build_type')}; "
        f"flags `{ctx(results, 'cxx_flags')}`; Quadrant scalar {ctx(results, 'quadrant_real')}")
    out(f"- commit: {ctx(results, 'commit')}")
    out(f"- date: {ctx(results, 'date')}")
    if busy_count(results):
        out(f"- **busy machine run**: {busy_count(results)} busy process(es) (shell busy loops) ran beside "
            "every benchmark (`tools/quadrant bench --busy`)")
    if ctx(results, 'frame_rate', '0') not in ('0', ''):
        out(f"- **frame loop**: every step followed by sleeping to the next frame boundary at "
            f"{ctx(results, 'frame_rate')} Hz (`--frame-rate`); only the steps are timed")
    out(f"- load: 1-minute load average {ctx(results, 'load_avg_before')} before the run")
    reps = sorted({s['reps'] for s in results.stats.values()})
    out(f"- settings: {ctx(results, 'steps')} timed steps after {ctx(results, 'warmup')} untimed warm-up "
        f"steps, seed {ctx(results, 'seed')}, repetitions per benchmark: {', '.join(map(str, reps)) or 'none'}; "
        f"figures are medians over repetitions (real time)")
    for scene in results.scenes:
        desc = c.get(f"scene_{scene}")
        if desc:
            out(f"- scene `{scene}`: {desc}")
    out(f"- source: `{os.path.basename(source)}`")
    out("")
    out("Notes: Bullet is serial here (Debian builds Bullet 3.24 without `BT_THREADSAFE`, so its "
        "multithreaded world runs on one thread) and Box2D 2.4.1 is single-threaded: both appear "
        "at 1 thread only. Cells for thread counts above the machine's core count are marked "
        "(oversubscribed): their speed-ups are not parallel scaling (Quadrant's pool starts no more "
        "threads than cores: there its 3- and 4-block partitions run on the 2 threads). '-' means the engine does not "
        "run that many threads; 'n/a' means not run (unsupported or missing). "
        "`quadrant` runs the default "
        "deterministic scheme (bit-identical for any thread count), `quadrant (quadrants)` the "
        "thesis's quadrant partition.")
    for e in results.engines:
        notes = c.get(f"engine_notes_{e}")
        if notes:
            out(f"- {engine_title(e)} (`{e}`): {notes}")
    out("")

    threads = results.threads or [1]

    def over(t):
        return cores is not None and t > cores

    if any(s.get("bound") for k, s in results.stats.items() if k[3] > 1):
        out("Reading the speed-ups: '(bound B)' beside a speed-up is Quadrant's load-balance bound, "
            "measured in this run: the time of all its stages over their critical path (largest block "
            "of each parallel section plus every serial section), i.e. the speed-up its partition allows "
            "with a core per thread; it backs the oversubscribed figures. It is shown only where it was "
            "measured (Quadrant, 2 threads or more). '(work on 1 thread)' means the bound was 1.00: "
            "the steps ran on one thread (the task system runs a step alone on a busy machine, or the "
            "sections were too small to split), so that speed-up is not parallelism. A speed-up more "
            f"than {100 * (ABOVE_BOUND - 1):.0f} % above its bound is marked 'noise': the partition "
            "cannot give it, so one of the two runs was disturbed.")
        out("")

    for scene in results.scenes:
        noun = SCENE_NOUNS.get(scene, "bodies")
        fig = THESIS_FIGURES.get(scene)
        dense = ": dense; " in c.get(f"scene_{scene}", "")
        out(f"## {scene}" + (f" (thesis {fig})" if fig else "") + (" (dense, solver-bound)" if dense else ""))
        out("")
        for n in results.counts(scene):
            out(f"### {scene}, N = {n} {noun}")
            out("")
            head = ["engine"] + [f"steps/s {t}T" for t in threads] + [f"speed-up {t}T" for t in threads if t != 1]
            out("| " + " | ".join(head) + " |")
            out("|" + "---|" + "---:|" * (len(head) - 1))
            for e in results.engines:
                row = [engine_title(e)]
                base = results.get(scene, e, n, 1)
                anything = False
                for t in threads:
                    s = results.get(scene, e, n, t)
                    anything |= s is not None
                    cell = fmt_sps(s["sps"]) if s else ("-" if results.beyond_engine(e, t) else "n/a")
                    if s and over(t):
                        cell += " (oversubscribed)"
                    if s:
                        cell += flag_mark(flagged, (scene, e, n, t))
                    row.append(cell)
                for t in threads:
                    if t == 1:
                        continue
                    s = results.get(scene, e, n, t)
                    if s and base:
                        cell = speedup_cell(s["sps"] / base["sps"], s.get("bound"))
                        if over(t):
                            cell += " (oversubscribed)"
                        if (scene, e, n, t) in flagged or (scene, e, n, 1) in flagged:
                            cell += " (**noisy**)"
                    else:
                        cell = "-" if results.beyond_engine(e, t) else "n/a"
                    row.append(cell)
                if anything:
                    out("| " + " | ".join(row) + " |")
            out("")

    # Quadrant against each peer.
    quadrants = [e for e in results.engines if e.startswith("quadrant")]
    peers = [e for e in results.engines if not e.startswith("quadrant")]
    if quadrants and peers:
        for q in quadrants:
            out(f"## {engine_title(q)} (1 thread) / peer (1 thread), steps-per-second ratio")
            out("")
            out("Above 1: Quadrant steps faster than the peer. A ratio of two figures either of which is "
                "flagged is marked (**noisy**): not a result to quote.")
            if whole:
                out(f"**Every ratio here is flagged**: {'; '.join(whole)}.")
            out("")
            for scene in results.scenes:
                out(f"### {scene}")
                out("")
                out("| N | " + " | ".join(engine_title(p) for p in peers) + " |")
                out("|---:|" + "---:|" * len(peers))
                for n in results.counts(scene):
                    qs = results.get(scene, q, n, 1)
                    cells = []
                    for p in peers:
                        ps = results.get(scene, p, n, 1)
                        noisy = {(scene, q, n, 1), (scene, p, n, 1)} & set(flagged)
                        cells.append(f"{qs['sps'] / ps['sps']:.2f}" + (" (**noisy**)" if noisy else "")
                                     if qs and ps else "n/a")
                    out(f"| {n} | " + " | ".join(cells) + " |")
                out("")
            # Best thread count within the cores, each engine at its best.
            usable = [t for t in threads if not over(t)]
            if len(usable) > 1:
                out(f"### {engine_title(q)} at its best / peer at its best, thread counts up to {max(usable)} (not oversubscribed)")
                out("")
                for scene in results.scenes:
                    out(f"| {scene} N | " + " | ".join(engine_title(p) for p in peers) + " |")
                    out("|---:|" + "---:|" * len(peers))
                    for n in results.counts(scene):
                        def best(e):
                            """(steps/s, key) of the engine's best thread count, or (None, None)."""
                            vals = [(results.get(scene, e, n, t), (scene, e, n, t)) for t in usable]
                            vals = [(v["sps"], k) for v, k in vals if v]
                            return max(vals) if vals else (None, None)
                        qb, qk = best(q)
                        cells = []
                        for p in peers:
                            pb, pk = best(p)
                            noisy = {qk, pk} & set(flagged)
                            cells.append(f"{qb / pb:.2f}" + (" (**noisy**)" if noisy else "")
                                         if qb and pb else "n/a")
                        out(f"| {n} | " + " | ".join(cells) + " |")
                    out("")

    # Repetition spread and state hashes: how far to trust the figures.
    spread = [((s["max"] - s["min"]) / s["sps"], k) for k, s in results.stats.items() if s["reps"] > 1 and s["sps"] > 0]
    if spread:
        worst, key = max(spread)
        out("## Noise")
        out("")
        out(f"Median spread (max - min) / median over repetitions: {100 * statistics.median(x for x, _ in spread):.1f} %; "
            f"largest {100 * worst:.1f} % ({key[0]}/{key[1]}/n:{key[2]}/threads:{key[3]}).")
        out("")
    for line in flag_lines(results, flagged, "quiet-machine" if busy is not None else "benchmark"):
        out(line)
    if busy is not None:
        for line in busy_markdown(busy, cores):
            out(line)
    varying = []
    for scene in results.scenes:
        for e in results.engines:
            for n in results.counts(scene):
                labels = set()
                for t in threads:
                    s = results.get(scene, e, n, t)
                    if s:
                        labels.update(l for l in s["labels"] if l)
                if len(labels) > 1:
                    varying.append(f"{scene}/{e}/n:{n}")
    out("## State hashes")
    out("")
    if varying:
        out("The final state hash differs between repetitions or thread counts (not deterministic "
            "across them) for: " + ", ".join(f"`{v}`" for v in varying) + ".")
    else:
        out("Every engine's final state hash is the same over all repetitions and thread counts it ran.")
    out("")

    if results.unsupported or results.failed or results.errors:
        out("## Not run")
        out("")
        # Thread counts above an engine's maximum: one line per engine, not one per benchmark.
        limited, other = {}, []
        for u in results.unsupported:
            m = re.match(r"^\s*[^/]+/(?P<engine>[^/]+)/n:\d+/threads:(?P<t>\d+): .*runs at most (?P<max>\d+) thread", u)
            if m:
                limited.setdefault((m.group("engine"), m.group("max")), set()).add(int(m.group("t")))
            else:
                other.append(u.strip())
        for (engine, most), ts in sorted(limited.items()):
            out(f"- unsupported: `{engine}` runs at most {most} thread(s): thread counts "
                f"{', '.join(map(str, sorted(ts)))} not run")
        for u in other:
            out(f"- unsupported: {u}")
        for u in results.errors:
            out(f"- error: {u.strip()}")
        for name, msg in results.failed:
            out(f"- failed: {name}: {msg}")
        out("")
    return "\n".join(lines)


# ---- Plots -----------------------------------------------------------------------------------

# A figure per scene: one panel per thread count (small multiples: with 1-4 threads x 5 engines
# x min-max bands in one axes the lines tangled), one legend above the panels, flagged points
# ringed with one legend entry, and a one-line footer in a margin of its own below the axis title
# (it used to list every flagged point, 51 on the circles plot, over the axis numbers and title).
# layout_problems() checks that no text overlaps another; tests/tools/plot_layout_test.py runs it.

FOOTER_FONTSIZE = 7


def plot_footer(results, scene=None):
    """One line: where the figure comes from, and what is flagged (the list is in speedup.md)."""
    reps = sorted({st["reps"] for st in results.stats.values()})
    busy = busy_count(results)
    parts = [f"{ctx(results, 'machine', ctx(results, 'host_name'))} ({ctx(results, 'cpu_model')}, "
             f"{results.cores or '?'} cores)", f"commit {ctx(results, 'commit')}", str(ctx(results, "date"))[:10],
             f"{ctx(results, 'steps')} steps after {ctx(results, 'warmup')} warm-up",
             f"median of {'/'.join(map(str, reps)) or '?'} repetitions"]
    if busy:
        parts.append(f"BUSY: {busy} busy loop{'s' if busy != 1 else ''} beside the run")
    flagged = flag_summary(results, scene)
    if flagged:
        parts.append("FLAGGED: " + flagged + "; see speedup.md")
    return "  \u00b7  ".join(parts)


def flag_summary(results, scene):
    """"12 noisy points (ringed), load 5.63 before the run > 2 cores", or ""."""
    noisy = [k for k in flags(results) if scene is None or k[0] == scene]
    parts = []
    if noisy:
        parts.append(f"{len(noisy)} noisy point{'s' if len(noisy) != 1 else ''} (ringed)")
    try:
        before = float(results.context.get("load_avg_before"))
    except (TypeError, ValueError):
        before = None
    if run_flags(results) and before is not None:
        parts.append(f"load {before:.2f} before the run > {results.cores} cores")
    return ", ".join(parts)


def panel_grid(n):
    """(rows, columns) of the small multiples for n thread counts."""
    if n <= 3:
        return 1, n
    if n == 4:
        return 2, 2
    return (n + 2) // 3, 3


def layout_problems(fig):
    """Pairs of texts or boxes of a drawn figure that overlap, or that leave the figure: the
    suptitle, legends, axes (with their tick labels and titles), axis labels and footer."""
    renderer = fig.canvas.get_renderer()
    boxes = []
    for i, ax in enumerate(fig.axes):
        if ax.get_visible():
            boxes.append((f"panel {i + 1}", ax.get_tightbbox(renderer)))
    for legend in fig.legends:
        boxes.append(("legend", legend.get_window_extent(renderer)))
    for text in fig.texts:  # the suptitle, supxlabel, supylabel and footer among them
        if text.get_text():
            boxes.append((f"text {text.get_text()[:30]!r}", text.get_window_extent(renderer)))
    problems = []
    fig_box = fig.bbox
    for name, box in boxes:
        if box.x0 < fig_box.x0 - 1 or box.y0 < fig_box.y0 - 1 or box.x1 > fig_box.x1 + 1 or box.y1 > fig_box.y1 + 1:
            problems.append(f"{name} leaves the figure")
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            (a, ba), (b, bb) = boxes[i], boxes[j]
            if a.startswith("panel") and b.startswith("panel"):
                continue  # shared axes: neighbours' boxes touch by design
            if ba.overlaps(bb):
                problems.append(f"{a} overlaps {b}")
    return problems


def plot_scene(results, scene, path):
    """Draws fps_<scene>.png; returns layout_problems() of the figure (empty when it is clean)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FixedLocator, FuncFormatter, LogLocator, NullFormatter

    flagged = flags(results)
    threads = [t for t in results.threads if any(results.get(scene, e, n, t) for e in results.engines
                                                  for n in results.counts(scene))] or [1]
    rows, cols = panel_grid(len(threads))
    # Margins in inches, so the footer and legend keep their room whatever the panel count.
    width = 4.2 * cols + 1.0
    # The legend: the engines drawn, the band and (if any) the noisy ring, in rows of legend_cols.
    legend_cols = 4 if width >= 10 else 3
    legend_entries = len([e for e in results.engines if any(results.get(scene, e, n, t)
                                                              for n in results.counts(scene) for t in threads)])
    legend_entries += 1 + any(k[0] == scene for k in flagged)
    legend_rows = -(-legend_entries // legend_cols)
    top_in, bottom_in, left_in, right_in = 0.72 + 0.16 * legend_rows, 0.8, 0.95, 0.2
    height = 3.2 * rows + top_in + bottom_in
    fig, axes = plt.subplots(rows, cols, figsize=(width, height), dpi=110, sharex=True, sharey=True,
                             squeeze=False)
    fig.subplots_adjust(left=left_in / width, right=1 - right_in / width, bottom=bottom_in / height,
                        top=1 - top_in / height, wspace=0.08, hspace=0.22)
    counts = results.counts(scene)
    drawn_engines, any_flag = [], False
    for idx, ax in enumerate(axes.flat):
        if idx >= len(threads):
            ax.set_visible(False)
            continue
        t = threads[idx]
        over = results.cores is not None and t > results.cores
        not_here = []
        for e in results.engines:
            colour, marker, _ = plot_style.style(e)
            stats = [(n, results.get(scene, e, n, t)) for n in counts]
            stats = [(n, st) for n, st in stats if st]
            if not stats:
                if any(results.get(scene, e, n, 1) for n in counts):
                    not_here.append(e)
                continue
            xs = [n for n, _ in stats]
            ax.plot(xs, [st["sps"] for _, st in stats], marker=marker, color=colour, markersize=4.5,
                    linewidth=1.4)
            if any(st["reps"] > 1 for _, st in stats):
                ax.fill_between(xs, [st["min"] for _, st in stats], [st["max"] for _, st in stats],
                                color=colour, alpha=0.12, linewidth=0)
            noisy = [(n, st["sps"]) for n, st in stats if (scene, e, n, t) in flagged]
            if noisy:
                any_flag = True
                ax.scatter([n for n, _ in noisy], [v for _, v in noisy], s=110, facecolors="none",
                           edgecolors="black", linewidths=1.1, zorder=5)
            if e not in drawn_engines:
                drawn_engines.append(e)
        title = f"{t} thread{'s' if t != 1 else ''}"
        if over:
            title += f" (oversubscribed: {results.cores} cores)"
        ax.set_title(title, fontsize=9.5)
        if not_here:
            ax.text(0.02, 0.02, "not run at " + title.split(" (")[0] + ": "
                    + ", ".join(plot_style.style(e)[2].split(" (")[0] for e in not_here),
                    transform=ax.transAxes, fontsize=7, color="dimgray", ha="left", va="bottom")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="major", linestyle="-", alpha=0.4)
        ax.grid(True, which="minor", linestyle=":", alpha=0.25)
        ax.tick_params(labelsize=8)
    ax0 = axes.flat[0]
    # Labels at 1, 2 and 5 per decade: a plot spanning less than a decade still gets several.
    ax0.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax0.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax0.yaxis.set_minor_formatter(NullFormatter())
    if counts:
        ax0.xaxis.set_major_locator(FixedLocator(counts))
        ax0.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax0.xaxis.set_minor_locator(FixedLocator([]))
        ax0.xaxis.set_minor_formatter(NullFormatter())
        if len(counts) == 1:
            ax0.set_xlim(counts[0] / 1.5, counts[0] * 1.5)
        else:
            ax0.set_xlim(counts[0] / 1.15, counts[-1] * 1.15)
    noun = SCENE_NOUNS.get(scene, "bodies")
    title = f"Steps per second vs number of {noun}"
    fig_ref = THESIS_FIGURES.get(scene)
    title += f" ({scene}; cf. thesis {fig_ref})" if fig_ref else f" ({scene})"
    busy = busy_count(results)
    if busy:
        title += f"; BUSY MACHINE: {busy} busy process{'es' if busy != 1 else ''} beside the run"
    fig.suptitle(title, fontsize=11, y=1 - 0.1 / height, va="top")
    fig.supxlabel(f"number of {noun} (N)", fontsize=9, y=0.28 / height, va="bottom")
    fig.supylabel("steps per second (median over repetitions)", fontsize=9, x=0.08 / width, ha="left")
    handles = [plt.Line2D([], [], color=plot_style.style(e)[0], marker=plot_style.style(e)[1],
                          linestyle="-", label=plot_style.style(e)[2]) for e in drawn_engines]
    handles.append(matplotlib.patches.Patch(color="gray", alpha=0.25, label="min-max over repetitions"))
    if any_flag:
        handles.append(plt.Line2D([], [], marker="o", markersize=9, markerfacecolor="none",
                                  markeredgecolor="black", linestyle="none",
                                  label="noisy (spread > 50 % or other load; speedup.md)"))
    if drawn_engines:
        fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 1 - 0.42 / height),
                   ncol=legend_cols, fontsize=7.5, frameon=False,
                   columnspacing=1.2, handlelength=2.0)
    else:
        ax0.text(0.5, 0.5, "no data", transform=ax0.transAxes, ha="center")
    footer = fig.text(0.5 * left_in / width, 0.08 / height, plot_footer(results, scene),
                      fontsize=FOOTER_FONTSIZE, ha="left", va="bottom",
                      color="black" if flag_summary(results, scene) else "dimgray")
    # One line that fits: smaller type for a long one rather than a second line over the axes.
    fig.canvas.draw()
    room = fig.bbox.width * (1 - left_in / width)
    wide = footer.get_window_extent(fig.canvas.get_renderer()).width
    if wide > room:
        footer.set_fontsize(max(5.0, FOOTER_FONTSIZE * room / wide * 0.98))
    fig.canvas.draw()
    problems = layout_problems(fig)
    fig.savefig(path)
    plt.close(fig)
    return problems


# ---- Main ------------------------------------------------------------------------------------


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("json", nargs="?", help="Google Benchmark JSON from quadrant_bench")
    ap.add_argument("--check", metavar="FILE", help="validate FILE's structure and exit")
    ap.add_argument("--out", metavar="DIR", help="output directory (default: the JSON's directory)")
    ap.add_argument("--quiet", action="store_true", help="do not print the tables")
    ap.add_argument("--busy", metavar="FILE", help="the same suite's JSON from `bench --busy K`: adds the busy machine table")
    args = ap.parse_args(argv)

    if args.check:
        problems = check(args.check)
        if problems:
            print(f"bench_report: {args.check}: {len(problems)} problem(s):", file=sys.stderr)
            for p in problems[:50]:
                print(f"  - {p}", file=sys.stderr)
            if len(problems) > 50:
                print(f"  ... and {len(problems) - 50} more", file=sys.stderr)
            return 1
        print(f"bench_report: {args.check}: OK")
        return 0
    if not args.json:
        ap.error("give a JSON file (or --check FILE)")

    try:
        data = gbench_json.load(args.json)
    except gbench_json.GBenchError as e:
        print(f"bench_report: {e}", file=sys.stderr)
        return 1
    results = Results(data)
    if not results.stats:
        print(f"bench_report: {args.json}: no usable benchmark rows", file=sys.stderr)
    out_dir = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out_dir, exist_ok=True)

    busy = None
    if args.busy:
        try:
            busy = Results(gbench_json.load(args.busy))
        except gbench_json.GBenchError as e:
            print(f"bench_report: {e}", file=sys.stderr)
            return 1
    text = markdown(results, args.json, busy)
    with open(os.path.join(out_dir, "speedup.md"), "w", encoding="utf-8") as f:
        f.write(text + "\n")
    written = [os.path.join(out_dir, "speedup.md")]
    for scene in results.scenes:
        path = os.path.join(out_dir, f"fps_{scene}.png")
        for problem in plot_scene(results, scene, path):
            print(f"bench_report: warning: {os.path.basename(path)}: {problem}", file=sys.stderr)
        written.append(path)
    if not args.quiet:
        print(text)
    print("bench_report: wrote " + ", ".join(written), file=sys.stderr)
    return 0 if results.stats else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
