#!/usr/bin/python3
"""Turn a quadrant_bench Google Benchmark JSON into speed-up tables and FPS plots.

Usage (run with Debian's interpreter, /usr/bin/python3, which sees python3-matplotlib):

    /usr/bin/python3 tools/bench_report.py bench.json [--out DIR]
        writes DIR/speedup.md and DIR/fps_<scene>.png for every scene in the run and prints
        the Markdown to stdout (DIR defaults to the JSON's directory)
    /usr/bin/python3 tools/bench_report.py --check bench.json
        validates the JSON's structure; exits 1 with a message naming the first problems

Figures: for every benchmark <scene>/<engine>/n:<N>/threads:<T> the MEDIAN steps per second
over its repetitions, computed here from the per-repetition rows (Google Benchmark's own
aggregate rows are ignored, except that a file holding only aggregates is read through its
_median rows). Partial data (engines, thread counts or sizes missing) gives partial tables,
never a crash.
"""

import argparse
import datetime
import json
import math
import os
import re
import statistics
import sys

# <scene>/<engine>/n:<N>/threads:<T>, then what Google Benchmark appends: /iterations:<k>,
# /real_time or /manual_time, and _<aggregate> on aggregate rows. Engine names may hold
# variants ("quadrant:pgs").
NAME_RE = re.compile(
    r"^(?P<scene>[A-Za-z0-9_.\-]+)/(?P<engine>[A-Za-z0-9_.:\-]+)/n:(?P<n>\d+)/threads:(?P<threads>\d+)"
    r"(?:/iterations:\d+)?(?:/(?:real_time|manual_time))?(?:_(?P<aggregate>[A-Za-z0-9]+))?$"
)
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


class ReportError(Exception):
    pass


def load_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except OSError as e:
        raise ReportError(f"{path}: cannot read: {e}")
    except json.JSONDecodeError as e:
        raise ReportError(f"{path}: not valid JSON: {e}")


def parse_name(name):
    m = NAME_RE.match(name or "")
    if not m:
        return None
    return m.group("scene"), m.group("engine"), int(m.group("n")), int(m.group("threads")), m.group("aggregate")


def is_aggregate(row):
    if row.get("run_type") == "aggregate":
        return True
    parsed = parse_name(row.get("name", ""))
    return bool(parsed and parsed[4])


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
    """Returns a list of problems (empty if the file is well formed)."""
    problems = []
    try:
        data = load_json(path)
    except ReportError as e:
        return [str(e)]
    if not isinstance(data, dict):
        return ["top level is not a JSON object"]
    if not isinstance(data.get("context"), dict):
        problems.append('missing or malformed "context" object')
    benches = data.get("benchmarks")
    if not isinstance(benches, list):
        problems.append('missing or malformed "benchmarks" array')
        return problems
    if not benches:
        problems.append('"benchmarks" is empty: nothing was run')
    iterations = 0
    for i, row in enumerate(benches):
        if not isinstance(row, dict):
            problems.append(f"benchmarks[{i}] is not an object")
            continue
        name = row.get("name", "")
        parsed = parse_name(name)
        if not parsed:
            problems.append(f"benchmarks[{i}]: name {name!r} does not match <scene>/<engine>/n:<int>/threads:<int>")
            continue
        if row.get("error_occurred"):
            problems.append(f"{name}: failed: {row.get('error_message', 'no message')}")
            continue
        aggregate = row.get("aggregate_name") or parsed[4]
        if is_aggregate(row):
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
        isinstance(r, dict) and (r.get("aggregate_name") == "median" or r.get("name", "").endswith("_median"))
        for r in benches
    ):
        problems.append("no per-repetition rows and no _median rows")
    return problems


# ---- Collecting ------------------------------------------------------------------------------


class Results:
    def __init__(self, data):
        self.context = data.get("context", {}) if isinstance(data, dict) else {}
        rows = data.get("benchmarks", []) if isinstance(data, dict) else []
        reps = {}  # key -> list of rows
        medians = {}  # key -> aggregate median row
        self.failed = []
        for row in rows:
            if not isinstance(row, dict):
                continue
            parsed = parse_name(row.get("name", ""))
            if not parsed:
                continue
            key = parsed[:4]
            if row.get("error_occurred"):
                self.failed.append((row.get("name"), row.get("error_message", "")))
                continue
            if is_aggregate(row):
                if (row.get("aggregate_name") or parsed[4]) == "median":
                    medians[key] = row
                continue
            reps.setdefault(key, []).append(row)
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
        for row in rows:
            parsed = parse_name(row.get("name", "")) if isinstance(row, dict) else None
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
        for key in ("cores", "num_cpus"):
            try:
                v = int(self.context.get(key))
                if v > 0:
                    return v
            except (TypeError, ValueError):
                pass
        return None

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


def markdown(results, source):
    c = results.context
    cores = results.cores
    lines = []
    out = lines.append
    out("# Steps per second and thread speed-up")
    out("")
    out(f"- machine: {ctx(results, 'machine', ctx(results, 'host_name'))}")
    out(f"- CPU: {ctx(results, 'cpu_model')}, cores: {cores if cores else 'unknown'}")
    out(f"- compiler: {ctx(results, 'compiler')}; build type {ctx(results, 'build_type')}; "
        f"flags `{ctx(results, 'cxx_flags')}`; Quadrant scalar {ctx(results, 'quadrant_real')}")
    out(f"- commit: {ctx(results, 'commit')}")
    out(f"- date: {ctx(results, 'date')}")
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
        "(oversubscribed): their speed-ups are not parallel scaling. '-' means the engine does not "
        "run that many threads; 'n/a' means not run (unsupported or missing). "
        "'bound' is Quadrant's measured load-balance bound at that thread count: the time "
        "of all its stages (thread CPU time when oversubscribed, wall time per block otherwise) over their critical path (largest thread share of each parallel section "
        "plus every serial section), i.e. the speed-up its partition allows with a core per thread; "
        "on this machine it backs the oversubscribed figures. `quadrant` runs the default "
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
                    row.append(cell)
                for t in threads:
                    if t == 1:
                        continue
                    s = results.get(scene, e, n, t)
                    if s and base:
                        cell = f"{s['sps'] / base['sps']:.2f}x"
                        if s.get("bound"):
                            cell += f" (bound {s['bound']:.2f})"
                        if over(t):
                            cell += " (oversubscribed)"
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
            out("Above 1: Quadrant steps faster than the peer.")
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
                        cells.append(f"{qs['sps'] / ps['sps']:.2f}" if qs and ps else "n/a")
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
                            vals = [results.get(scene, e, n, t) for t in usable]
                            vals = [v["sps"] for v in vals if v]
                            return max(vals) if vals else None
                        qb = best(q)
                        cells = []
                        for p in peers:
                            pb = best(p)
                            cells.append(f"{qb / pb:.2f}" if qb and pb else "n/a")
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

MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*"]
STYLES = {1: "-", 2: "--", 3: "-.", 4: ":"}


def plot_scene(results, scene, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6), dpi=110)
    colours = plt.rcParams["axes.prop_cycle"].by_key().get("color", ["C0", "C1", "C2", "C3"])
    drawn = 0
    for i, e in enumerate(results.engines):
        for t in results.threads:
            pts = [(n, results.get(scene, e, n, t)) for n in results.counts(scene)]
            pts = [(n, s["sps"]) for n, s in pts if s]
            if not pts:
                continue
            xs, ys = zip(*pts)
            over = results.cores is not None and t > results.cores
            label = f"{engine_title(e)}, {t} thread{'s' if t > 1 else ''}" + (" (oversubscribed)" if over else "")
            ax.plot(xs, ys, marker=MARKERS[i % len(MARKERS)], linestyle=STYLES.get(t, (0, (1, 1 + t))),
                    color=colours[i % len(colours)], label=label, markersize=5, linewidth=1.4,
                    alpha=0.6 if over else 1.0)
            drawn += 1
    ax.set_xscale("log")
    ax.set_yscale("log")
    noun = SCENE_NOUNS.get(scene, "bodies")
    title = f"Steps per second vs number of {noun}"
    fig_ref = THESIS_FIGURES.get(scene)
    ax.set_title(title + (f" ({scene}; cf. thesis {fig_ref})" if fig_ref else f" ({scene})"))
    ax.set_xlabel(f"number of {noun} (N)")
    ax.set_ylabel("steps per second (median over repetitions)")
    ax.grid(True, which="major", linestyle="-", alpha=0.4)
    ax.grid(True, which="minor", linestyle=":", alpha=0.25)
    counts = results.counts(scene)
    if counts:
        from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

        ax.xaxis.set_major_locator(FixedLocator(counts))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
    if drawn:
        ax.legend(fontsize=7, loc="best", ncol=2 if drawn > 8 else 1)
    else:
        ax.text(0.5, 0.5, "no data", transform=ax.transAxes, ha="center")
    footer = (f"machine {ctx(results, 'machine', ctx(results, 'host_name'))} ({ctx(results, 'cpu_model')}, "
              f"{results.cores or '?'} cores); commit {ctx(results, 'commit')}; {ctx(results, 'steps')} steps "
              f"after {ctx(results, 'warmup')} warm-up; {ctx(results, 'date')}. Bullet serial (no BT_THREADSAFE), "
              f"Box2D 2.4.1 single-threaded.")
    fig.text(0.01, 0.01, footer, fontsize=6.5, ha="left", va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path)
    plt.close(fig)


# ---- Main ------------------------------------------------------------------------------------


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("json", nargs="?", help="Google Benchmark JSON from quadrant_bench")
    ap.add_argument("--check", metavar="FILE", help="validate FILE's structure and exit")
    ap.add_argument("--out", metavar="DIR", help="output directory (default: the JSON's directory)")
    ap.add_argument("--quiet", action="store_true", help="do not print the tables")
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
        data = load_json(args.json)
    except ReportError as e:
        print(f"bench_report: {e}", file=sys.stderr)
        return 1
    if not isinstance(data, dict) or not isinstance(data.get("benchmarks"), list):
        print(f"bench_report: {args.json}: not a Google Benchmark JSON (no \"benchmarks\")", file=sys.stderr)
        return 1
    results = Results(data)
    if not results.stats:
        print(f"bench_report: {args.json}: no usable benchmark rows", file=sys.stderr)
    out_dir = args.out or os.path.dirname(os.path.abspath(args.json))
    os.makedirs(out_dir, exist_ok=True)

    text = markdown(results, args.json)
    with open(os.path.join(out_dir, "speedup.md"), "w", encoding="utf-8") as f:
        f.write(text + "\n")
    written = [os.path.join(out_dir, "speedup.md")]
    for scene in results.scenes:
        path = os.path.join(out_dir, f"fps_{scene}.png")
        plot_scene(results, scene, path)
        written.append(path)
    if not args.quiet:
        print(text)
    print("bench_report: wrote " + ", ".join(written), file=sys.stderr)
    return 0 if results.stats else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
