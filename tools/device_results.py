#!/usr/bin/python3
"""Commit a lent machine's benchmark outputs as results/<machine>/: one merged bench.json with
its speedup.md and fps_*.png, the machine's description and the pool's overhead, and (with
--comparisons) a section of comparisons.md against the older commits the same call ran.

Usage (Debian's /usr/bin/python3, which sees python3-matplotlib):

    /usr/bin/python3 tools/device_results.py DIR --machine NAME [--out results/NAME]
                     [--comparisons [--title TITLE] [--script RUN.sh]] [--no-index]
    /usr/bin/python3 tools/device_results.py DIR --machine NAME --ab BASE_TAG HEAD_TAG
                     [--out results/NAME] [--title TITLE] [--script RUN.sh] [--no-index]

Contract. DIR holds one device call's outputs: Google Benchmark JSON files of quadrant_bench
(one per run, "sets"), their .log files, machine.txt (nproc, lscpu, uptime) and optionally
task_overhead.json (quadrant_task_overhead). The head commit is the commit most of the
quadrant_bench sets name in their context. bench.json merges the head's sets in the order they
ran (context date), keeping every per-repetition row, except
  - a frame loop's set (context frame_rate not 0: not back-to-back steps),
  - a set run with the pool's statistics on (its .log holds "pool N: life ..." lines: an
    instrumented pool),
  - the rows of a benchmark that an earlier set already holds (a second set with other --steps
    would mix windows and state hashes; the earlier set's rows are kept).
Every row keeps its own steps and warmup counters. The context is the first set's, with the
machine set to NAME, scenes, engines, counts and thread counts the union, and device_sets
(each set's file, date and command as its context gives it), device_skipped (what was left
out and why); steps and warmup name every value when the sets differ.
It then copies machine.txt and task_overhead.json, runs tools/bench_report.py on bench.json
(speedup.md, fps_<scene>.png in the same folder) and tools/results_index.py for the checkout
that holds the folder (when it is results/<name>/).

--comparisons appends (or replaces, by its title) a section of OUT/comparisons.md: ms per step
medians over repetitions (the rows' ms_per_step) of the head against every other commit's sets
in DIR, cell by cell; a frame loop's set against the back-to-back figures; the pool counters of
poolstats_*.log; the commands (--script: the lines of the run script that made the sets). All
figures come from the files; rerun it on a second device call's DIR with another --title.

--ab BASE_TAG HEAD_TAG (interleaved pairs): writes only a section of OUT/comparisons.md (appended,
or replaced by its title; bench.json, speedup.md and the plots stay as they are). DIR's sets named
<group>_<BASE_TAG>_<N>.json and <group>_<HEAD_TAG>_<N>.json are pairs (pair N of group: the base
set, then the head set, run back to back); one commit per tag. One table per group, a row per
scene/engine/count/threads: base and head ms per step (median over the pairs of each set's
median), the median of the per-pair head/base ratios and each pair's, the solve stage's ms
(stage_solve_ms medians) base -> head, and whether the state hashes (labels) are one between base
and head and the same as at the row's fewest threads. Besides: the machine (machine.txt, against
the one in OUT), the sets' dates and the order within each pair, the base's 1-thread medians
against OUT/bench.json's (an earlier call: another VM instance may run at another speed, so only
the ratios within one call compare), the head's frame loops (context frame_rate) against its
back-to-back medians over the pairs, the pool counters of the head's poolstats_*.log, the
commands (--script lines and each set's context) and DIR's other sets, named as left out. The
default title: "<cores> cores, <head> against <base>: interleaved pairs (<day>)".

Refuses (one line on stderr, exit 2, nothing written) when DIR holds no quadrant_bench JSON, the
head's sets name more than one CPU or core count, or OUT already holds JSON of another machine;
with --ab also when no pair is found, the tags are equal or a tag's sets name two commits.
"""

import argparse
import collections
import json
import os
import re
import shutil
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import gbench_json  # noqa: E402  the one reader of Google Benchmark JSON in tools/

PYTHON = "/usr/bin/python3"
POOL_LINE_RE = re.compile(r"^pool (\d+): (.*)$", re.M)


class Refusal(Exception):
    pass


# ---- reading DIR ---------------------------------------------------------------------------


class Set:
    """One quadrant_bench JSON file of DIR."""

    def __init__(self, path, data):
        self.path = path
        self.name = os.path.basename(path)
        self.stem = self.name[:-len(".json")]
        self.data = data
        self.context = data.get("context") if isinstance(data.get("context"), dict) else {}
        self.commit = str(self.context.get("commit") or "unknown")
        self.date = str(self.context.get("date") or "")
        self.rows = [r for r in data["benchmarks"] if isinstance(r, dict)]
        log = path[:-len(".json")] + ".log"
        try:
            with open(log, encoding="utf-8", errors="replace") as f:
                self.log = f.read()
        except OSError:
            self.log = ""

    def frame_rate(self):
        try:
            return float(self.context.get("frame_rate", 0) or 0)
        except (TypeError, ValueError):
            return 0.0

    def pool_stats(self):
        return bool(POOL_LINE_RE.search(self.log))

    def key(self, row):
        return gbench_json.parse_quadrant_name(row.get("run_name") or row.get("name", ""))

    def iterations(self):
        """(key, row) of every per-repetition row."""
        for r in self.rows:
            if r.get("error_occurred") or gbench_json.aggregate_of(r):
                continue
            k = self.key(r)
            if k:
                yield k, r

    def repetitions(self):
        counts = collections.Counter(k for k, _ in self.iterations())
        return sorted(set(counts.values()))

    def command(self):
        """The quadrant_bench command as the set's context gives it."""
        c = self.context
        counts = sorted({k[2] for k, _ in self.iterations()})
        reps = self.repetitions()
        parts = ["quadrant_bench", f"--scenes {c.get('scenes', '?')}", f"--engines {c.get('engines', '?')}",
                 f"--counts {','.join(map(str, counts))}", f"--threads {c.get('thread_counts', '?')}",
                 f"--steps {c.get('steps', '?')}", f"--warmup {c.get('warmup', '?')}"]
        if self.frame_rate():
            parts.append(f"--frame-rate {c.get('frame_rate')}")
        if reps and reps != [1]:
            parts.append("--benchmark_repetitions=" + "/".join(map(str, reps)))
        return " ".join(parts)


def read_sets(directory):
    """Every quadrant_bench JSON of DIR, by date; refuses when there is none."""
    if not os.path.isdir(directory):
        raise Refusal(f"{directory}: not a directory")
    names = sorted(n for n in os.listdir(directory) if n.endswith(".json"))
    if not names:
        raise Refusal(f"{directory}: no JSON files")
    sets = []
    for n in names:
        path = os.path.join(directory, n)
        try:
            data = gbench_json.load(path)
        except gbench_json.GBenchError:
            continue
        s = Set(path, data)
        if any(True for _ in s.iterations()):
            sets.append(s)
    if not sets:
        raise Refusal(f"{directory}: no quadrant_bench JSON (rows named <scene>/<engine>/n:<N>/threads:<T>)")
    return sorted(sets, key=lambda s: (s.date, s.name))


def head_commit(sets):
    counts = collections.Counter(s.commit for s in sets)
    best = max(counts.values())
    # Ties: the commit of the first set that ran.
    return next(s.commit for s in sets if counts[s.commit] == best)


# ---- merging -------------------------------------------------------------------------------


def union_list(values):
    out = []
    for v in values:
        for x in str(v or "").split(","):
            if x and x not in out:
                out.append(x)
    return ",".join(out)


def merge(sets, head, machine):
    """(bench.json's data, [(file, reason)] left out, [used sets])."""
    skipped, used = [], []
    for s in sets:
        if s.commit != head:
            skipped.append((s.name, f"commit {s.commit}, not the head's {head}"))
        elif s.frame_rate():
            skipped.append((s.name, f"a {s.context.get('frame_rate')} Hz frame loop, not back-to-back steps"))
        elif s.pool_stats():
            skipped.append((s.name, "run with the pool's statistics on (its .log has the pool counters)"))
        else:
            used.append(s)
    if not used:
        raise Refusal("no set of the head commit is left to merge: " + "; ".join(f"{n}: {r}" for n, r in skipped))
    cpus = {(str(s.context.get("cpu_model")), str(s.context.get("num_cpus"))) for s in used}
    if len(cpus) > 1:
        raise Refusal("the sets name more than one machine: " + ", ".join(f"{m} ({n} cpus)" for m, n in sorted(cpus)))

    rows, owner = [], {}
    for s in used:
        dropped = collections.Counter()
        for k, r in s.iterations():
            if owner.get(k, s.name) != s.name:
                dropped[k] += 1
                continue
            owner[k] = s.name
            rows.append(r)
        if dropped:
            owners = sorted({owner[k] for k in dropped})
            steps_there = "/".join(str(u.context.get("steps")) for u in used if u.name in owners)
            skipped.append((s.name, f"{sum(dropped.values())} rows of {len(dropped)} benchmarks that "
                            f"{', '.join(owners)} (run earlier) already holds, left out so that no benchmark mixes "
                            f"windows (steps {s.context.get('steps')} here, {steps_there} there): "
                            + ", ".join(f"{k[0]}/{k[1]}/n:{k[2]}/threads:{k[3]}" for k in sorted(dropped))))
    ctx = dict(used[0].context)
    ctx["machine"] = machine
    for key in ("scenes", "engines", "thread_counts"):
        ctx[key] = union_list(s.context.get(key) for s in used)
    ctx["counts"] = ",".join(dict.fromkeys(c for s in used for c in str(s.context.get("counts", "")).split(",") if c))
    for s in used:  # per-scene and per-engine descriptions: the first set's that has one
        for k, v in s.context.items():
            if (k.startswith("scene_") or k.startswith("engine_")) and k not in ctx:
                ctx[k] = v
    for key in ("errors", "unsupported"):
        ctx[key] = ";".join(dict.fromkeys(x for s in used for x in str(s.context.get(key) or "").split(";") if x.strip()))
    for key in ("steps", "warmup"):
        values = list(dict.fromkeys(str(s.context.get(key)) for s in used))
        if len(values) > 1:
            nums = sorted(int(float(v)) for v in values if re.fullmatch(r"[0-9.]+", v))
            # Short (the plots' footers quote it); each set's value is in device_sets, each row's in its counter.
            ctx[key] = (f"{nums[0]}-{nums[-1]}" if nums else "/".join(values)) + " (per set)"
    ctx["device_sets"] = "; ".join(f"{s.name} ({s.date}): {s.command()}" for s in used)
    ctx["device_skipped"] = "; ".join(f"{n}: {r}" for n, r in skipped)
    return {"context": ctx, "benchmarks": rows}, skipped, used


# ---- the out folder ------------------------------------------------------------------------


def check_out(out, machine, cpus):
    """Refuses when OUT already holds JSON of another machine."""
    if not os.path.isdir(out):
        return
    for dirpath, _, files in os.walk(out):
        for n in files:
            if not n.endswith(".json"):
                continue
            path = os.path.join(dirpath, n)
            try:
                with open(path, encoding="utf-8") as f:
                    data = json.load(f)
            except (OSError, ValueError):
                continue
            ctx = data.get("context") if isinstance(data, dict) and isinstance(data.get("context"), dict) else {}
            m = ctx.get("machine")
            if m not in (None, "", machine):
                raise Refusal(f"{out}: {os.path.relpath(path, out)} is machine {m!r}, not {machine!r}: "
                              "the folder would mix machines")
            n_cpus = ctx.get("num_cpus")
            if n_cpus not in (None, "") and cpus and str(n_cpus) != str(cpus):
                raise Refusal(f"{out}: {os.path.relpath(path, out)} ran on {n_cpus} CPUs, these sets on {cpus}: "
                              "the folder would mix machines")


def results_root(out):
    """The checkout whose results/ holds OUT (OUT = <root>/results/<machine>), else None."""
    parent = os.path.dirname(os.path.abspath(out))
    return os.path.dirname(parent) if os.path.basename(parent) == "results" else None


# ---- comparisons.md ------------------------------------------------------------------------


def ms_medians(sets=(), rows=()):
    """{key: (median ms per step, repetitions, steps)} over the sets' per-repetition rows (or the
    given rows of a merged file)."""
    values, steps = collections.defaultdict(list), collections.defaultdict(set)
    pairs = [(k, r) for s in sets for k, r in s.iterations()]
    pairs += [(gbench_json.parse_quadrant_name(r.get("run_name") or r.get("name", "")), r) for r in rows]
    for k, r in pairs:
        v = gbench_json.ms_per_step(r)
        if k and v is not None:
            values[k].append(v)
            steps[k].add(r.get("steps"))
    return {k: (statistics.median(v), len(v), steps[k]) for k, v in values.items()}


def fmt_ms(v):
    return "-" if v is None else (f"{v:.3f}" if v < 10 else f"{v:.2f}")


def key_name(k):
    return f"{k[0]}/{k[1]}/n:{k[2]}"


def machine_facts(directory):
    """'Intel(R) Xeon(R) Processor, 16 CPUs (nproc 16), KVM guest, 1 NUMA node(s), L3 300 MiB'."""
    try:
        with open(os.path.join(directory, "machine.txt"), encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        return "machine.txt missing"

    def field(name):
        m = re.search(rf"^{re.escape(name)}:\s*(.+)$", text, re.M)
        return m.group(1).strip() if m else None
    first = text.split("\n", 1)[0].strip()
    parts = [field("Model name") or "CPU unknown"]
    if first.isdigit():
        parts.append(f"nproc {first}")
    if field("Core(s) per socket") and field("Socket(s)"):
        parts.append(f"{field('Core(s) per socket')} cores per socket x {field('Socket(s)')}, "
                     f"{field('Thread(s) per core')} thread(s) per core")
    if field("Hypervisor vendor"):
        parts.append(f"{field('Hypervisor vendor')} guest")
    if field("NUMA node(s)"):
        parts.append(f"{field('NUMA node(s)')} NUMA node(s)")
    if field("L3 cache"):
        parts.append(f"L3 {field('L3 cache')}")
    return ", ".join(parts)


def script_lines(script, stems):
    """The lines of a run script that made the given sets: the lines naming a set (a $var may
    stand for part of a name), the for loops around them and the variables they use."""
    try:
        with open(script, encoding="utf-8") as f:
            lines = f.read().split("\n")
    except OSError:
        return []

    def names_set(line):
        for token in re.split(r"[\s\"']+", line):
            if not token or token.startswith("#"):
                continue
            literal = re.sub(r"\$\{\w+\}|\$\w+", "", token)
            if not re.search(r"[A-Za-z]{3}", literal):
                continue  # a token that is only variables names nothing
            pattern = re.escape(token)
            pattern = re.sub(r"\\\$\\\{\w+\\\}|\\\$\w+", r"\\w+", pattern)
            if any(re.fullmatch(pattern, stem) for stem in stems):
                return True
        return False
    keep = {i for i, line in enumerate(lines) if names_set(line) and not line.lstrip().startswith("#")}
    for i in sorted(keep):  # the for loop a kept line is in
        for j in range(i - 1, max(-1, i - 4), -1):
            if re.match(r"^\s*for\b.*\bdo\s*$", lines[j]):
                keep.add(j)
                for m in range(i + 1, min(len(lines), i + 4)):
                    if re.match(r"^\s*done\b", lines[m]):
                        keep.add(m)
                        break
                break
    for _ in range(3):  # the variables the kept lines use, and theirs
        used = {v for i in keep for v in re.findall(r"\$\{?(\w+)", lines[i])}
        for i, line in enumerate(lines):
            m = re.match(r"^\s*(\w+)=", line)
            if m and m.group(1) in used and not line.lstrip().startswith("#"):
                for v in re.findall(r"(?:^|;\s*)(\w+)=", line):
                    if v in used:
                        keep.add(i)
    return [lines[i] for i in sorted(keep)]


def script_quote(script, stems):
    """The Commands paragraph quoting SCRIPT's lines that made the sets STEMS, as a sh block."""
    return ([f"The run script `{script}` (not committed), run as `bash {script}` from the repository root; its "
             "lines that made these sets (`b NAME COMMIT BINARY ARGS` runs BINARY with ARGS and "
             "`--benchmark_out=NAME.json`):", "", "```sh"] +
            (script_lines(script, stems) or ["# (no line of the script names these sets)"]) + ["```", ""])


def pool_rows(directory):
    """(file, threads, fields) of every pool line with steps in DIR's poolstats_*.log."""
    out = []
    for n in sorted(os.listdir(directory)):
        if not (n.startswith("poolstats") and n.endswith(".log")):
            continue
        with open(os.path.join(directory, n), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for m in POOL_LINE_RE.finditer(text):
            body = m.group(2)

            def num(pattern):
                g = re.search(pattern, body)
                return g.group(1) if g else "?"
            fields = {
                "steps": num(r"\bsteps (\d+)"), "alone": num(r"\(alone (\d+)\)"), "jobs": num(r"\bjobs (\d+)"),
                "serial": num(r"\bserial (\d+)"), "wait": num(r"\bwait ([0-9.]+) ms"),
                "waits>1ms": num(r"waits>1ms (\d+)"), "marks": num(r"\bmarks (\d+) \("),
                "marks by stall/idle/queue": "/".join(re.search(
                    r"marks by stall (\d+) idle (\d+) queue (\d+)", body).groups())
                if re.search(r"marks by stall \d+ idle \d+ queue \d+", body) else "?",
                "parallel-job time": num(r"parallel-job time ([0-9.]+) ms"), "life": num(r"\blife ([0-9.]+) ms"),
                "steers": num(r"\bsteers (\d+)"),
            }
            if fields["steps"] not in ("0", "?"):
                out.append((n, int(m.group(1)), fields))
    return out


def frame_loop_tables(s, back, heading, back_note):
    """A frame-loop set's section: under ### HEADING, per benchmark, its median ms per step against
    BACK's back-to-back medians ({key + (threads,): (ms, reps, ...)}), their ratio and the late frames;
    BACK_NOTE says where the back-to-back figures come from."""
    fm = ms_medians(sets=[s])
    late = collections.defaultdict(list)
    for k, r in s.iterations():
        if isinstance(r.get("late_frames"), (int, float)):
            late[k].append(r["late_frames"])
    lines = [f"### {heading}", "",
             f"The frame loop sleeps to the next frame boundary after every step (`--frame-rate "
             f"{s.context.get('frame_rate')}`, repetitions {'/'.join(map(str, s.repetitions()))}); only the "
             f"steps are timed. {back_note} Ratio = frame loop / back-to-back.", ""]
    for k3 in dict.fromkeys(k[:3] for k in fm):
        threads = sorted(k[3] for k in fm if k[:3] == k3)
        lines += [f"#### `{key_name(k3)}`", "", "| | " + " | ".join(f"{t}T" for t in threads) + " |",
                  "|---|" + "---:|" * len(threads),
                  "| frame loop | " + " | ".join(fmt_ms(fm[k3 + (t,)][0]) for t in threads) + " |",
                  "| back-to-back | " + " | ".join(fmt_ms(back.get(k3 + (t,), (None,))[0]) for t in threads) + " |",
                  "| ratio | " + " | ".join(f"{fm[k3 + (t,)][0] / back[k3 + (t,)][0]:.2f}" if k3 + (t,) in back
                                           else "-" for t in threads) + " |"]
        if late:
            lines.append("| late frames | " + " | ".join(
                f"{statistics.median(late[k3 + (t,)]):.0f}" if late.get(k3 + (t,)) else "-" for t in threads) + " |")
        lines.append("")
    return lines


def comparisons(directory, sets, head, data, skipped, title, script):
    """The section's Markdown lines."""
    lines = [f"## {title}", ""]
    dates = sorted(s.date for s in sets if s.date)
    span = (f"{dates[0][:10]} {dates[0][11:16]}-{dates[-1][11:16]} UTC (the sets' context dates)"
            if dates else "unknown")
    bases = [c for c in dict.fromkeys(s.commit for s in sets) if c != head]
    # The head: bench.json's rows (one set per benchmark); the bases: their own sets.
    med = {head: ms_medians(rows=data["benchmarks"])}
    for c in bases:
        med[c] = ms_medians(sets=[s for s in sets if s.commit == c and not s.frame_rate() and not s.pool_stats()])
    compared = [k for c in bases for k in med[c]]
    reps = {c: sorted({med[c][k][1] for k in compared if k in med[c]}) for c in [head] + bases}
    lines += [f"Machine: {machine_facts(directory)} (machine.txt beside this file). Date: {span}. "
              "One device call ran every set below in turn, each cell's repetitions back to back "
              "(repetitions per cell compared here: " + ", ".join(
                  f"{c} {'/'.join(map(str, reps[c])) or '-'}" for c in [head] + bases) +
              "); not interleaved, so a drift of the machine during the call is in the ratios. "
              "Figures: median over repetitions of the rows' ms_per_step (wall time per timed step, ms); "
              "ratio = head / base (below 1: the head is faster). Columns: every thread count a base ran, "
              "and the head's others with the same timed steps.", ""]

    # Head against every base commit, benchmark by benchmark.
    lines += [f"### ms per step, {head} against " + " and ".join(bases), ""]
    for k3 in dict.fromkeys((k[0], k[1], k[2]) for c in bases for k in med[c]):
        base_steps = {st for c in bases for k, v in med[c].items() if k[:3] == k3 for st in v[2]}
        threads = sorted({k[3] for c in bases for k in med[c] if k[:3] == k3} |
                         {k[3] for k, v in med[head].items() if k[:3] == k3 and v[2] <= base_steps})
        steps = "/".join(f"{x:g}" for x in sorted(base_steps) if isinstance(x, (int, float)))
        lines += [f"#### `{key_name(k3)}` ({steps} timed steps)", "",
                  "| commit | reps | " + " | ".join(f"{t}T" for t in threads) + " |",
                  "|---|---:|" + "---:|" * len(threads)]
        for c in [head] + bases:
            cells = [med[c].get(k3 + (t,)) for t in threads]
            if not any(cells):
                continue
            r = "/".join(map(str, sorted({x[1] for x in cells if x})))
            lines.append(f"| {c} | {r} | " + " | ".join(fmt_ms(x[0] if x else None) for x in cells) + " |")
        for c in bases:
            cells = []
            for t in threads:
                a, b = med[head].get(k3 + (t,)), med[c].get(k3 + (t,))
                cells.append(f"{a[0] / b[0]:.2f}" if a and b else "-")
            if any(x != "-" for x in cells):
                lines.append(f"| {head} / {c} | | " + " | ".join(cells) + " |")
        lines.append("")

    # Frame loops against back-to-back steps.
    for s in sets:
        if s.commit != head or not s.frame_rate():
            continue
        lines += frame_loop_tables(
            s, med[head], f"{s.context.get('frame_rate')} Hz frame loop (`{s.name}`) against back-to-back steps",
            "Back-to-back: the same benchmark in bench.json.")

    # Pool counters.
    pools = pool_rows(directory)
    if pools:
        stats_sets = {s.stem: s for s in sets if s.pool_stats()}
        cols = ["steps", "alone", "jobs", "serial", "marks", "marks by stall/idle/queue", "waits>1ms", "wait",
                "parallel-job time", "life", "steers"]
        lines += ["### Pool counters (`QUADRANT_POOL_STATS=1`)", "",
                  "The pool's own counters, printed when it is destroyed (poolstats_*.log; a pool line with no "
                  "step, the first of each log, left out). 'steps alone': steps the caller ran without the "
                  "workers; 'marks': the pool marking itself busy (steps then run alone); times in ms. ms/step: "
                  "the set's own row (one repetition, the counters on).", "",
                  "| file | threads | ms/step | " + " | ".join(cols) + " |", "|---|---:|---:|" + "---:|" * len(cols)]
        for n, t, f in pools:
            s = stats_sets.get(n[:-len(".log")])
            ms = statistics.median(v for v in (gbench_json.ms_per_step(r) for _, r in s.iterations()) if v is not None) if s else None
            lines.append(f"| `{n}` | {t} | {fmt_ms(ms)} | " + " | ".join(f[c] for c in cols) + " |")
        lines.append("")

    # Commands.
    lines += ["### Commands", ""]
    if script:
        lines += script_quote(script, [s.stem for s in sets])
    lines += ["Each set as its JSON context records it:", ""]
    for s in sets:
        lines.append(f"- `{s.name}` ({s.commit}, {s.date}): `{s.command()}`")
    lines += ["", "Left out of bench.json (and so of speedup.md and the plots):", ""]
    lines += [f"- {n}: {r}" for n, r in skipped] or ["- nothing"]
    lines.append("")
    return lines



def write_comparisons(path, machine, section):
    title = section[0]
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError:
        text = (f"# Comparisons on {machine}\n\nSummaries of runs on this machine whose raw files are not "
                "committed (tools/device_results.py --comparisons), one section per device call.\n")
    body = "\n".join(section).rstrip("\n") + "\n"
    start = text.find(title + "\n")
    if start >= 0:
        nxt = re.search(r"^## ", text[start + len(title):], re.M)
        end = start + len(title) + nxt.start() if nxt else len(text)
        text = text[:start] + body + ("\n" if nxt else "") + text[end:]
    else:
        text = text.rstrip("\n") + "\n\n" + body
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


# ---- --ab: interleaved pairs ---------------------------------------------------------------


def ab_pairs(sets, base_tag, head_tag):
    """({group: [(pair, base set, head set)]} by pair number, groups in the order they ran;
    [(file, reason)] of the tagged sets without a partner)."""
    rx = re.compile(rf"^(?P<group>.+)_(?P<tag>{re.escape(base_tag)}|{re.escape(head_tag)})_(?P<pair>\d+)$")
    found = collections.defaultdict(dict)
    for s in sets:
        m = rx.match(s.stem)
        if m:
            found[(m.group("group"), int(m.group("pair")))][m.group("tag")] = s
    groups, unpaired = {}, []
    for (g, p), d in sorted(found.items(), key=lambda kv: min(s.date for s in kv[1].values())):
        if base_tag in d and head_tag in d:
            groups.setdefault(g, []).append((p, d[base_tag], d[head_tag]))
        else:
            for s in d.values():
                unpaired.append((s.name, f"no {head_tag if base_tag in d else base_tag} set of pair {p}"))
    for g in groups:
        groups[g].sort(key=lambda x: x[0])
    return groups, unpaired


def set_medians(s, field=None):
    """{key: median over the set's per-repetition rows} of ms_per_step (or of the counter field)."""
    values = collections.defaultdict(list)
    for k, r in s.iterations():
        v = gbench_json.ms_per_step(r) if field is None else r.get(field)
        if isinstance(v, (int, float)):
            values[k].append(float(v))
    return {k: statistics.median(v) for k, v in values.items()}


def set_labels(s):
    out = collections.defaultdict(set)
    for k, r in s.iterations():
        if r.get("label"):
            out[k].add(str(r["label"]))
    return out


def fmt_ratio(v):
    return "-" if v is None else f"{v:.2f}"


def ab_check(sets, groups, base_tag, head_tag):
    """The base and head commits; refuses when there is no pair or a tag names two commits."""
    if not groups:
        raise Refusal(f"no pair of sets named <group>_{base_tag}_<N>.json and <group>_{head_tag}_<N>.json")
    commits = {}
    for i, tag in ((1, base_tag), (2, head_tag)):
        cs = sorted({pair[i].commit for g in groups.values() for pair in g})
        if len(cs) > 1:
            raise Refusal(f"the {tag} sets name more than one commit: " + ", ".join(cs))
        commits[tag] = cs[0]
    paired = [s for g in groups.values() for pair in g for s in pair[1:]]
    cpus = {(str(s.context.get("cpu_model")), str(s.context.get("num_cpus"))) for s in paired}
    if len(cpus) > 1:
        raise Refusal("the sets name more than one machine: " + ", ".join(f"{m} ({n} cpus)" for m, n in sorted(cpus)))
    return commits[base_tag], commits[head_tag]


def ab_section(directory, sets, base_tag, head_tag, title, script, first_bench=None, out=None):
    """The Markdown lines of an interleaved A/B section: every <group>_<BASE>_<N> set against
    <group>_<HEAD>_<N>, the head's frame loops and pool counters."""
    groups, unpaired = ab_pairs(sets, base_tag, head_tag)
    base, head = ab_check(sets, groups, base_tag, head_tag)
    paired = [s for g in groups.values() for pair in g for s in pair[1:]]
    frames = [s for s in sets if s not in paired and s.commit == head and s.frame_rate()]
    stats = [s for s in sets if s not in paired and s.commit == head and s.pool_stats()]
    stats_stems = {s.stem for s in stats}
    pools = [p for p in pool_rows(directory) if p[0][:-len(".log")] in stats_stems]
    used = sorted(paired + frames + stats, key=lambda s: (s.date, s.name))
    others = [s.name for s in sets if s not in used]

    dates = sorted(s.date for s in used if s.date)
    span = (f"{dates[0][:10]} {dates[0][11:16]}-{dates[-1][11:16]} UTC (the start dates in the contexts of the "
            "sets below)" if dates else "unknown")
    order_ok = all(b.date < h.date for g in groups.values() for _, b, h in g)
    n_pairs = sorted({len(g) for g in groups.values()})
    facts = machine_facts(directory)
    if out and os.path.isfile(os.path.join(out, "machine.txt")):
        where = ("the same description as the machine.txt beside this file" if machine_facts(out) == facts
                 else "NOT the description of the machine.txt beside this file: " + machine_facts(out))
    else:
        where = "no machine.txt beside this file to compare"
    lines = [f"## {title}", "",
             f"Machine: {facts} (machine.txt of this call, not committed; {where}). Date: {span}. Commits: base {base} (files `*_{base_tag}_N.json`), "
             f"head {head} (files `*_{head_tag}_N.json`). Interleaved pairs: for N = 1, 2, ... the pair's base "
             f"set ran, then at once its head set (" + ("base first in every pair, by the contexts' dates"
                                                          if order_ok else "NOT base first in every pair: see the dates below")
             + f"); {'/'.join(map(str, n_pairs))} pairs per group; each set holds one repetition per benchmark, "
             "so a drift of the machine falls on both sides of a pair. Figures: ms per timed step (the rows' "
             "ms_per_step); base ms and head ms: median over the pairs; ratio = head / base (below 1: the head is "
             "faster), median of the per-pair ratios, then each pair's in pair order; solve: the stage_solve_ms "
             "counter (ms per step in the solve stage), medians over the pairs, base -> head. State hash: the "
             "rows' label; 'base = head' when every base and head set of the row has the one label, 'across "
             "threads' when that label is the one of the row's fewest threads.", ""]

    # Against the earlier call's bench.json: the same machine kind, another VM instance?
    if first_bench:
        first_rows = first_bench.get("benchmarks", [])
        first_ctx = first_bench.get("context", {})
        first = ms_medians(rows=first_rows)
        base_med = {}
        for g in groups.values():
            for k in dict.fromkeys(k for _, b, _ in g for k in set_medians(b)):
                vals = [set_medians(b).get(k) for _, b, _ in g]
                vals = [v for v in vals if v is not None]
                if vals:
                    base_med.setdefault(k, statistics.median(vals))
        ones = sorted(k for k in base_med if k[3] == 1 and k in first)
        if ones:
            ratios = [base_med[k] / first[k][0] for k in ones]
            verdict = ("this call's VM instance ran slower than the earlier call's at every one of them"
                       if all(r > 1 for r in ratios) else
                       "this call's VM instance ran faster than the earlier call's at every one of them"
                       if all(r < 1 for r in ratios) else "the two calls' VM instances differ, one way or the other")
            same = "the same commit" if str(first_ctx.get("commit")) == base else f"commit {first_ctx.get('commit')}"
            lines += [f"Against the earlier call (bench.json beside this file: {same}, "
                      f"{str(first_ctx.get('date', '?'))[:16].replace('T', ' ')} UTC), 1 thread, this call's base "
                      "median against bench.json's: " + "; ".join(
                          f"{key_name(k)} {fmt_ms(base_med[k])} against {fmt_ms(first[k][0])} ms "
                          f"(x{base_med[k] / first[k][0]:.2f})" for k in ones) +
                      f". So {verdict}: absolute ms are not comparable across the two calls, only the ratios "
                      "within this call.", ""]

    head_back = {}
    for g, pairs in groups.items():
        bm = [set_medians(b) for _, b, _ in pairs]
        hm = [set_medians(h) for _, _, h in pairs]
        bs = [set_medians(b, "stage_solve_ms") for _, b, _ in pairs]
        hs = [set_medians(h, "stage_solve_ms") for _, _, h in pairs]
        bl = [set_labels(b) for _, b, _ in pairs]
        hl = [set_labels(h) for _, _, h in pairs]
        keys = list(dict.fromkeys(k for m in bm + hm for k in m))
        scene_order = list(dict.fromkeys(k[0] for k in keys))
        keys.sort(key=lambda k: (scene_order.index(k[0]), k[1], k[2], k[3]))
        files = f"{g}_{base_tag}_N.json, {g}_{head_tag}_N.json, N = " + ", ".join(str(p) for p, _, _ in pairs)
        lines += [f"### `{g}`: {files}", "",
                  "| benchmark | threads | base ms | head ms | head/base (median) | per pair | solve ms base -> head "
                  "| hash base = head | across threads |",
                  "|---|---:|---:|---:|---:|---:|---:|---|---|"]

        def med(ms, k):
            vals = [m[k] for m in ms if k in m]
            return statistics.median(vals) if vals else None

        def one_label(k):
            labels = set().union(*(d.get(k, set()) for d in bl + hl))
            return next(iter(labels)) if len(labels) == 1 else None
        for k in keys:
            b, h = med(bm, k), med(hm, k)
            if h is not None:
                head_back[k] = (h, len([m for m in hm if k in m]))
            per = [m_h[k] / m_b[k] if k in m_h and k in m_b else None for m_b, m_h in zip(bm, hm)]
            got = [r for r in per if r is not None]
            solve = f"{fmt_ms(med(bs, k))} -> {fmt_ms(med(hs, k))}" if med(bs, k) is not None else "-"
            lab = one_label(k)
            if lab:
                eq = f"yes `{lab[:8]}`"
            else:
                bset = set().union(*(d.get(k, set()) for d in bl))
                hset = set().union(*(d.get(k, set()) for d in hl))
                eq = ("no: base " + "/".join(f"`{x[:8]}`" for x in sorted(bset)) + ", head " +
                      "/".join(f"`{x[:8]}`" for x in sorted(hset)))
            fewest = min(t for (s_, e_, n_, t) in keys if (s_, e_, n_) == k[:3])
            ref = one_label(k[:3] + (fewest,))
            across = (("ref" if lab else "-") if k[3] == fewest else
                      "yes" if lab and lab == ref else "no" if lab and ref else "-")
            lines.append(f"| {key_name(k)} | {k[3]} | {fmt_ms(b)} | {fmt_ms(h)} | "
                         f"{fmt_ratio(statistics.median(got) if got else None)} | "
                         + " / ".join(fmt_ratio(r) for r in per) + f" | {solve} | {eq} | {across} |")
        lines.append("")

    # The head's frame loops against its back-to-back medians over the pairs.
    for s in frames:
        lines += frame_loop_tables(
            s, head_back, f"{s.context.get('frame_rate')} Hz frame loop of {head} (`{s.name}`) against its "
            "back-to-back steps",
            f"Back-to-back: {head}'s median over the pairs above (its `*_{head_tag}_N.json`).")

    # The head's pool counters.
    if pools:
        by_stem = {s.stem: s for s in stats}
        cols = ["steps", "alone", "jobs", "serial", "marks", "marks by stall/idle/queue", "waits>1ms", "wait",
                "parallel-job time", "life", "steers"]
        lines += [f"### Pool counters of {head} (`QUADRANT_POOL_STATS=1`)", "",
                  "The pool's own counters, printed when it is destroyed (poolstats_*.log; a pool line with no "
                  "step, the first of each log, left out). 'alone': steps the caller ran without the workers; "
                  "'marks': the pool marking itself busy (steps then run alone); times in ms. ms/step: the set's "
                  "own row (one repetition, the counters on); back-to-back: the same benchmark's head median over "
                  "the pairs above.", "",
                  "| file | threads | ms/step | back-to-back | " + " | ".join(cols) + " |",
                  "|---|---:|---:|---:|" + "---:|" * len(cols)]
        for n, t, f in pools:
            s = by_stem[n[:-len(".log")]]
            own = set_medians(s)
            ms = statistics.median(own.values()) if own else None
            back = [head_back[k][0] for k in own if k in head_back]
            lines.append(f"| `{n}` | {t} | {fmt_ms(ms)} | {fmt_ms(back[0] if len(back) == 1 else None)} | "
                         + " | ".join(f[c] for c in cols) + " |")
        lines.append("")

    # Commands.
    lines += ["### Commands", ""]
    if script:
        lines += script_quote(script, [s.stem for s in used])
    lines += ["Each set as its JSON context records it (a pair's two sets: one line when their commands agree):", ""]
    for g, pairs in groups.items():
        for p, b, h in pairs:
            cmd = b.command() if b.command() == h.command() else f"{b.command()}` / `{h.command()}"
            lines.append(f"- `{b.name}` ({b.commit}, {b.date}), `{h.name}` ({h.commit}, {h.date}): `{cmd}`")
    for s in sorted(frames + stats, key=lambda s: (s.date, s.name)):
        lines.append(f"- `{s.name}` ({s.commit}, {s.date}): `{s.command()}`"
                     + (" with QUADRANT_POOL_STATS=1" if s in stats else ""))
    lines += ["", "Not in this section: " + ("; ".join(f"{n} ({r})" for n, r in unpaired) + "; " if unpaired else "")
              + (", ".join(f"`{n}`" for n in others if n not in {u for u, _ in unpaired}) or "nothing")
              + ". Nothing of this call is in bench.json, speedup.md or the plots beside this file.", ""]
    return lines


# ---- main ----------------------------------------------------------------------------------


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dir", help="the device call's outputs (quadrant_bench JSON, .log, machine.txt)")
    ap.add_argument("--machine", required=True, help="the machine's name (tools/quadrant's machine_name())")
    ap.add_argument("--out", help="the folder to write (default: results/NAME of this checkout)")
    ap.add_argument("--comparisons", action="store_true", help="add a section to OUT/comparisons.md")
    ap.add_argument("--title", help="that section's title (default: cores, commits, date)")
    ap.add_argument("--script", help="the run script whose lines made the sets (quoted in the section)")
    ap.add_argument("--ab", nargs=2, metavar=("BASE_TAG", "HEAD_TAG"),
                    help="interleaved pairs <group>_BASE_TAG_<N>.json / <group>_HEAD_TAG_<N>.json: only a section "
                         "of OUT/comparisons.md (bench.json, speedup.md and the plots untouched)")
    ap.add_argument("--no-index", action="store_true", help="do not regenerate results/README.md")
    args = ap.parse_args(argv)
    out = args.out or os.path.join(HERE, "..", "results", args.machine)
    if args.ab:
        return main_ab(args, out)
    try:
        sets = read_sets(args.dir)
        head = head_commit(sets)
        data, skipped, used = merge(sets, head, args.machine)
        check_out(out, args.machine, data["context"].get("num_cpus"))
    except Refusal as e:
        print(f"device_results: {e}", file=sys.stderr)
        return 2

    os.makedirs(out, exist_ok=True)
    bench = os.path.join(out, "bench.json")
    with open(bench, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    written = [bench]
    for n in ("machine.txt", "task_overhead.json"):
        if os.path.isfile(os.path.join(args.dir, n)):
            shutil.copyfile(os.path.join(args.dir, n), os.path.join(out, n))
            written.append(os.path.join(out, n))
    r = subprocess.run([PYTHON, os.path.join(HERE, "bench_report.py"), bench, "--out", out, "--quiet"])
    if r.returncode != 0:
        print("device_results: bench_report.py failed", file=sys.stderr)
        return 1
    if args.comparisons:
        cores = data["context"].get("cores") or data["context"].get("num_cpus")
        bases = [c for c in dict.fromkeys(s.commit for s in sets) if c != head]
        day = min(s.date for s in sets)[:10]
        title = args.title or f"{cores} cores, {head} against {' and '.join(bases)} (one lent call, {day})"
        path = os.path.join(out, "comparisons.md")
        write_comparisons(path, args.machine, comparisons(args.dir, sets, head, data, skipped, title, args.script))
        written.append(path)
    root = results_root(out)
    if root and not args.no_index:
        subprocess.run([PYTHON, os.path.join(HERE, "results_index.py"), "--root", root], check=False)
    print(f"device_results: head {head}; merged {len(used)} sets ({len(data['benchmarks'])} rows); left out "
          f"{len(skipped)}; wrote " + ", ".join(written) + " and the bench report", file=sys.stderr)
    return 0


def main_ab(args, out):
    """--ab: one section of OUT/comparisons.md from DIR's interleaved pairs; nothing else written."""
    base_tag, head_tag = args.ab
    try:
        if base_tag == head_tag:
            raise Refusal(f"--ab {base_tag} {head_tag}: the two tags must differ")
        sets = read_sets(args.dir)
        groups, _ = ab_pairs(sets, base_tag, head_tag)
        base, head = ab_check(sets, groups, base_tag, head_tag)
        paired = [s for g in groups.values() for pair in g for s in pair[1:]]
        check_out(out, args.machine, paired[0].context.get("num_cpus"))
        first = None
        bench = os.path.join(out, "bench.json")
        if os.path.isfile(bench):
            with open(bench, encoding="utf-8") as f:
                first = json.load(f)
        cores = paired[0].context.get("cores") or paired[0].context.get("num_cpus")
        day = min(s.date for s in paired)[:10]
        title = args.title or f"{cores} cores, {head} against {base}: interleaved pairs ({day})"
        section = ab_section(args.dir, sets, base_tag, head_tag, title, args.script, first, out)
    except (Refusal, OSError, ValueError) as e:
        print(f"device_results: {e}", file=sys.stderr)
        return 2
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "comparisons.md")
    write_comparisons(path, args.machine, section)
    root = results_root(out)
    if root and not args.no_index:
        subprocess.run([PYTHON, os.path.join(HERE, "results_index.py"), "--root", root], check=False)
    print(f"device_results: --ab {base}/{head}: {len(paired) // 2} pairs in {len(groups)} groups; wrote {path}",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
