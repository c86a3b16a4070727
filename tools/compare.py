#!/usr/bin/python3
"""Compare two Google Benchmark runs benchmark by benchmark: is NEW faster, slower or unchanged?

Usage (Debian's interpreter, which sees python3-scipy):

    /usr/bin/python3 tools/compare.py BASE NEW [--alpha 0.05] [--threshold 5]
                                               [--min-repetitions 9] [--allow-load] [--all]

BASE and NEW are Google Benchmark JSON files (--benchmark_out_format=json) or directories, in
which case every *.json directly inside is read and the repetitions of a benchmark found in
several files are pooled.

Per benchmark (paired by name, with Google Benchmark's suffixes such as /iterations:1 and
/real_time removed; aggregate rows _mean/_median/_stddev/_cv are ignored in favour of the
per-repetition rows):
  - the median time per step on each side: the ms_per_step counter when every row of both
    sides has it, else real_time (converted to ms);
  - the ratio NEW/BASE of the medians;
  - a two-sided Mann-Whitney U test over the repetitions (p value);
  - a verdict: "slower" or "faster" when p < alpha AND the medians differ by more than the
    threshold (a significant 2 % change under a 5 % threshold is "unchanged": it is real but
    too small to act on); "unchanged" otherwise; "inconclusive (too few repetitions)" when either
    side has fewer than --min-repetitions repetitions (with fewer, the test cannot reach
    significance reliably, and one noisy run would decide): not tested, so nothing is claimed;
  - "inconclusive (loaded)" when either side ran on a loaded machine (gbench_json's rule, the
    one bench_report.py flags by: the load average before the run above the core count, or
    other processes using more than 0.5 cores during a repetition): the same binary measured
    14-39 % "faster" at load 5.2 (issue #29 item 4). The table still says which way the medians
    went ("loaded; looked faster"). --allow-load gives the verdict anyway, marked "(loaded)":
    for comparisons whose two sides ran interleaved under the same deliberate load
    (tools/compare_commits.sh's busy sets).

Prints a Markdown table of the tested benchmarks (with --all, the untested ones too), one line
for those not tested (how many, and the repetitions it needs), then names every slower benchmark
and lists the benchmarks found on one side only. Exit status: 1 if any benchmark is slower; else
4 if any verdict was withheld because a side ran loaded; else 3 if any benchmark could not be
tested (too few repetitions); 0 if every benchmark was tested and none is slower; 2 on bad input
(a missing or unreadable file, a file that is not Google Benchmark JSON, no benchmark in
common).

Why Mann-Whitney U: benchmark times are not normal (a long right tail from preemption and
cache misses), so a t-test's assumptions do not hold; the rank test needs none (Google
Benchmark's own tools/compare.py uses it too).

The test is scipy.stats.mannwhitneyu; which of its methods is used is chosen here (see
mann_whitney_u). tests/tools/compare_test.py checks the p values against values computed once.
"""

import argparse
import glob
import math
import os
import statistics
import sys

import scipy.stats  # Debian python3-scipy (tools/quadrant setup installs it)

import gbench_json
from gbench_json import base_name  # noqa: F401  (compare.base_name: the pairing rule, tested)

TIME_UNITS_MS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}

# Context keys whose difference makes a comparison questionable: warned about on stderr.
CONTEXT_KEYS = ("machine", "cpu_model", "compiler", "cxx_flags", "build_type", "quadrant_real",
                "steps", "warmup", "seed")

# Exact p values are computed when there are no ties and m * n is at most this (m = n = 50:
# well under a second in scipy).
EXACT_MAX_PRODUCT = 2500


class InputError(Exception):
    """Bad input: reported on stderr, exit status 2."""


# ---- Mann-Whitney U ---------------------------------------------------------------------------


def mann_whitney_u(x, y, method="auto"):
    """Two-sided Mann-Whitney U test (scipy.stats.mannwhitneyu). Returns (U of x, p, method used).

    method: "exact" (no ties allowed), "asymptotic" (normal approximation with tie and continuity
    correction) or "auto": exact when there are no ties and len(x) * len(y) <= EXACT_MAX_PRODUCT.
    The choice is made here, not by scipy's own "auto", because scipy 1.10 (Debian bookworm)
    switches to the normal approximation as soon as a sample exceeds 8 values, and the usual
    sizes here are 9..50 repetitions, where the exact null distribution is cheap and right.
    scipy's exact test ignores ties, so with ties the normal approximation is used (as scipy's
    own "auto" does).
    """
    m, n = len(x), len(y)
    if m == 0 or n == 0:
        raise ValueError("mann_whitney_u: both samples need at least one value")
    values = list(x) + list(y)
    ties = len(set(values)) < len(values)
    if method == "auto":
        method = "exact" if not ties and m * n <= EXACT_MAX_PRODUCT else "asymptotic"
    if method not in ("exact", "asymptotic"):
        raise ValueError(f"mann_whitney_u: unknown method {method!r}")
    if method == "exact" and ties:
        raise ValueError("mann_whitney_u: the exact test needs samples without ties")
    if len(set(values)) == 1:  # every value equal: no evidence of any difference (scipy: nan)
        return m * n / 2, 1.0, method
    result = scipy.stats.mannwhitneyu(x, y, alternative="two-sided", method=method)
    return float(result.statistic), min(1.0, max(0.0, float(result.pvalue))), method


# ---- Reading Google Benchmark JSON ------------------------------------------------------------


class Side:
    """One side of the comparison: the repetitions of every benchmark, from one or more files."""

    def __init__(self, label, path):
        self.label = label
        self.path = path
        self.files = self._files(path)
        self.reps = {}        # name -> list of rows (per-repetition)
        self.medians = {}     # name -> aggregate _median row (used only if no repetitions)
        self.failed = {}      # name -> error message
        self.contexts = []
        self.load_problems = []  # why the whole side ran loaded (gbench_json.run_load_problems)
        self.loaded = {}      # name -> most cores other processes used beyond the limit
        for f in self.files:
            self._read(f)
        if not (self.reps or self.medians or self.failed):
            raise InputError(f"{label} {path}: no benchmark rows found")

    @staticmethod
    def _files(path):
        if os.path.isdir(path):
            files = sorted(glob.glob(os.path.join(path, "*.json")))
            if not files:
                raise InputError(f"{path}: directory holds no *.json file")
            return files
        if not os.path.exists(path):
            raise InputError(f"{path}: no such file or directory")
        return [path]

    def _read(self, path):
        try:
            data = gbench_json.load(path)
            rows = gbench_json.Rows(data, path, strict=True)
        except gbench_json.GBenchError as e:
            raise InputError(str(e))
        context = data.get("context") if isinstance(data.get("context"), dict) else {}
        if context:
            self.contexts.append(context)
        for reason in gbench_json.run_load_problems(context):
            self.load_problems.append(f"{os.path.basename(path)}: {reason}")
        busy = gbench_json.busy_processes(context)
        for name, reps in rows.reps.items():
            excess = [x for x in (gbench_json.others_cpu_excess(r, busy) for r in reps) if x is not None]
            if excess and max(excess) > gbench_json.OTHERS_LIMIT:
                self.loaded[name] = max(max(excess), self.loaded.get(name, 0.0))
        self.failed.update(rows.failed)
        self.medians.update(rows.medians)
        for name, reps in rows.reps.items():
            self.reps.setdefault(name, []).extend(reps)

    def names(self):
        return set(self.reps) | set(self.medians)

    def context_value(self, key):
        values = {str(c[key]) for c in self.contexts if key in c}
        return ", ".join(sorted(values)) if values else None


def row_ms(row, metric, where):
    """The row's time per step (ms): the ms_per_step counter or real_time in ms."""
    if metric == "ms_per_step":
        value = row.get("ms_per_step")
    else:
        unit = TIME_UNITS_MS.get(row.get("time_unit", "ns"))
        real = row.get("real_time")
        if unit is None:
            raise InputError(f"{where}: {row['name']}: unknown time_unit {row.get('time_unit')!r}")
        value = real * unit if isinstance(real, (int, float)) else None
    if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise InputError(f"{where}: {row['name']}: no usable {metric} (got {value!r})")
    return float(value)


# ---- Comparing --------------------------------------------------------------------------------


class Comparison:
    def __init__(self, name, base_values, new_values, base_median, new_median, metric,
                 p, verdict):
        self.name = name
        self.base_values, self.new_values = base_values, new_values
        self.base_median, self.new_median = base_median, new_median
        self.metric = metric
        self.p = p
        self.verdict = verdict

    @property
    def ratio(self):
        return self.new_median / self.base_median if self.base_median > 0 else math.inf


def load_of(name, base, new):
    """Why `name`'s comparison ran loaded ("" if it did not): a whole side, or other processes
    during its repetitions on a side."""
    why = []
    for side in (base, new):
        if side.load_problems:
            why.append(f"{side.label} loaded")
        elif name in side.loaded:
            why.append(f"{side.label}: other processes used {side.loaded[name]:.1f} cores")
    return "; ".join(why)


def compare_one(name, base, new, alpha, threshold, min_reps, allow_load=False):
    base_rows, new_rows = base.reps.get(name, []), new.reps.get(name, [])
    rows = base_rows + new_rows + [r for r in (base.medians.get(name), new.medians.get(name)) if r]
    metric = "ms_per_step" if all("ms_per_step" in r for r in rows) else "real_time"
    base_values = [row_ms(r, metric, base.path) for r in base_rows]
    new_values = [row_ms(r, metric, new.path) for r in new_rows]
    # A side with only aggregate rows still gives a median to show, but no test.
    base_median = (statistics.median(base_values) if base_values
                   else row_ms(base.medians[name], metric, base.path))
    new_median = (statistics.median(new_values) if new_values
                  else row_ms(new.medians[name], metric, new.path))
    p = None
    loaded = load_of(name, base, new)
    if len(base_values) < min_reps or len(new_values) < min_reps:
        verdict = "inconclusive (too few repetitions)"
    else:
        _, p, _ = mann_whitney_u(new_values, base_values)
        ratio = new_median / base_median if base_median > 0 else math.inf
        if p < alpha and ratio > 1 + threshold:
            verdict = "slower"
        elif p < alpha and ratio < 1 - threshold:
            verdict = "faster"
        else:
            verdict = "unchanged"
        if loaded:
            # No verdict from a loaded machine, unless asked for (and then marked).
            verdict = f"{verdict} (loaded)" if allow_load else f"inconclusive (loaded; looked {verdict})"
    c = Comparison(name, base_values, new_values, base_median, new_median, metric, p, verdict)
    c.loaded = loaded
    return c


def fmt_ms(v):
    return f"{v:.4g}"


def short_list(names, most=3):
    """At most `most` names, then how many more: one line whatever the count."""
    names = list(names)
    shown = ", ".join(names[:most])
    return shown + (f", ... ({len(names) - most} more)" if len(names) > most else "")


def render(base, new, results, only_base, only_new, alpha, threshold, min_reps, show_all=False,
           allow_load=False):
    lines = []
    commits = (base.context_value("commit") or "?", new.context_value("commit") or "?")
    lines.append(f"Comparison: BASE {base.path} (commit {commits[0]}) -> NEW {new.path} "
                 f"(commit {commits[1]})")
    lines.append(f"Two-sided Mann-Whitney U over repetitions; a change is reported when "
                 f"p < {alpha:g} and the medians differ by more than {threshold * 100:g} %; "
                 f"needs at least {min_reps} repetitions per side and a machine that was not loaded.")
    for side in (base, new):
        if side.load_problems:
            lines.append(f"**{side.label} ran loaded** ({'; '.join(side.load_problems)}): "
                         + ("verdicts given anyway (--allow-load), marked (loaded)." if allow_load else
                            "no verdict is given for it; re-run on a quiet machine."))
    lines.append("")
    few = [c for c in results if c.verdict.startswith("inconclusive (too few")]
    shown = results if show_all else [c for c in results if c not in few]
    if shown:
        lines.append("| benchmark | base ms/step | new ms/step | new/base | change | p | reps base/new | verdict |")
        lines.append("|---|---:|---:|---:|---:|---:|---:|---|")
    for c in shown:
        change = (c.ratio - 1) * 100
        p = "n/a" if c.p is None else f"{c.p:.3g}"
        unit = "" if c.metric == "ms_per_step" else " (real_time)"
        verdict = f"**{c.verdict}**" if c.verdict.split(" (")[0] in ("slower", "faster") else c.verdict
        lines.append(f"| {c.name}{unit} | {fmt_ms(c.base_median)} | {fmt_ms(c.new_median)} | "
                     f"{c.ratio:.3f} | {change:+.1f} % | {p} | {len(c.base_values)}/"
                     f"{len(c.new_values)} | {verdict} |")
    if shown:
        lines.append("")
    slower = [c for c in results if c.verdict.startswith("slower")]
    faster = [c for c in results if c.verdict.startswith("faster")]
    withheld = [c for c in results if c.verdict.startswith("inconclusive (loaded")]
    if slower:
        lines.append(f"SLOWER ({len(slower)}):")
        for c in slower:
            lines.append(f"  - {c.name} ({(c.ratio - 1) * 100:+.1f} %, p = {c.p:.3g})"
                         + (" (loaded)" if c.loaded else ""))
    elif withheld or few:
        lines.append("No tested benchmark is slower; INCONCLUSIVE: some were not judged (below).")
    else:
        lines.append("No benchmark is slower.")
    if faster:
        lines.append(f"Faster ({len(faster)}): " + ", ".join(c.name for c in faster))
    if withheld:
        looked = {}
        for c in withheld:
            key = c.verdict.split("looked ")[-1].rstrip(")")
            looked[key] = looked.get(key, 0) + 1
        lines.append(f"INCONCLUSIVE (loaded) ({len(withheld)}): no verdict, a side ran on a loaded machine "
                     f"(looked: {', '.join(f'{n} {k}' for k, n in sorted(looked.items()))}); "
                     "re-run both on a quiet machine, or give --allow-load if both ran under the same load.")
    if few:
        reps_base = sorted({len(c.base_values) for c in few})
        reps_new = sorted({len(c.new_values) for c in few})
        lines.append(f"Not tested ({len(few)} benchmark{'s' if len(few) != 1 else ''}: "
                     f"{short_list(c.name for c in few)}): a verdict needs {min_reps} repetitions per side, "
                     f"BASE has {'/'.join(map(str, reps_base))} and NEW {'/'.join(map(str, reps_new))}; "
                     f"record both with tools/quadrant bench --repetitions {min_reps} (bench --baseline and "
                     f"--compare run {min_reps} by default)" + ("" if show_all else "; --all lists them") + ".")
    for label, names in (("Only in BASE (not compared)", only_base),
                         ("Only in NEW (not compared)", only_new)):
        if names:
            lines.append(f"{label} ({len(names)}): " + short_list(sorted(names), 10))
    for side in (base, new):
        for name, msg in sorted(side.failed.items()):
            lines.append(f"Failed in {side.label} (not compared): {name}: {msg}")
    return "\n".join(lines)


def warn_context(base, new):
    for key in CONTEXT_KEYS:
        b, n = base.context_value(key), new.context_value(key)
        if b is not None and n is not None and b != n:
            print(f"compare: warning: {key} differs: BASE {b!r}, NEW {n!r}", file=sys.stderr)


def percent(text):
    try:
        value = float(text.rstrip("%").strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a percentage")
    if not 0 <= value < 100:
        raise argparse.ArgumentTypeError(f"{text!r} is not in [0, 100)")
    return value / 100


def probability(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number")
    if not 0 < value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not in (0, 1)")
    return value


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="compare.py",
        description="Compare two Google Benchmark JSON runs (files or directories of *.json).")
    parser.add_argument("base", metavar="BASE")
    parser.add_argument("new", metavar="NEW")
    parser.add_argument("--alpha", type=probability, default=0.05,
                        help="significance level of the Mann-Whitney U test (default 0.05)")
    parser.add_argument("--threshold", type=percent, default=0.05,
                        help="smallest change in %% of the median reported as slower/faster "
                             "(default 5)")
    parser.add_argument("--min-repetitions", type=int, default=9,
                        help="repetitions needed on each side for a verdict (default 9)")
    parser.add_argument("--allow-load", action="store_true",
                        help="give verdicts where a side ran loaded, marked (loaded): only for two "
                             "sides run interleaved under the same load")
    parser.add_argument("--all", action="store_true",
                        help="list the benchmarks not tested (too few repetitions) in the table too")
    args = parser.parse_args(argv)
    if args.min_repetitions < 1:
        parser.error("--min-repetitions must be >= 1")
    try:
        base = Side("BASE", args.base)
        new = Side("NEW", args.new)
        common = sorted(base.names() & new.names())
        if not common:
            raise InputError(f"no benchmark in common between {args.base} "
                             f"({len(base.names())} benchmarks) and {args.new} "
                             f"({len(new.names())} benchmarks)")
        results = [compare_one(name, base, new, args.alpha, args.threshold, args.min_repetitions,
                               args.allow_load)
                   for name in common]
    except InputError as e:
        print(f"compare: error: {e}", file=sys.stderr)
        return 2
    warn_context(base, new)
    print(render(base, new, results, base.names() - new.names(), new.names() - base.names(),
                 args.alpha, args.threshold, args.min_repetitions, args.all, args.allow_load))
    if any(c.verdict.startswith("slower") for c in results):
        return 1
    # A verdict withheld (loaded) or not tested (too few repetitions) is not "nothing found":
    # each its own status.
    if any(c.verdict.startswith("inconclusive (loaded") for c in results):
        return 4
    return 3 if any(c.p is None for c in results) else 0


if __name__ == "__main__":
    sys.exit(main())
