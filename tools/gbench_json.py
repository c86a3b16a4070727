"""The one reader of Google Benchmark JSON in tools/ (bench_report.py, compare.py, history.py):
no other tool opens such a file or walks its "benchmarks" list.

A quadrant_bench row is named <scene>/<engine>/n:<N>/threads:<T>, and Google Benchmark appends
what is not part of a benchmark's identity: /iterations:<k>, /repeats:<k>, /min_time:<t>,
/real_time, /manual_time or /process_time, and on aggregate rows _mean, _median, _stddev or _cv.
base_name() removes all of them, so every tool pairs and groups rows by the same name (the three
tools had three rules: bench_report accepted only /iterations and /real_time, history.py no
min_time, compare.py all of them).
"""

import json
import re

SUFFIX_RE = re.compile(
    r"/(?:iterations:\d+|repeats:\d+|min_time:[0-9.]+s?|min_warmup_time:[0-9.]+s?"
    r"|real_time|manual_time|process_time)$"
)
AGGREGATE_RE = re.compile(r"_(?P<aggregate>mean|median|stddev|cv)$")
QUADRANT_NAME_RE = re.compile(
    r"^(?P<scene>[A-Za-z0-9_.\-]+)/(?P<engine>[A-Za-z0-9_.:+\-]+)/n:(?P<n>\d+)/threads:(?P<threads>\d+)$")
TIME_UNITS_S = {"ns": 1e-9, "us": 1e-6, "ms": 1e-3, "s": 1.0}


class GBenchError(Exception):
    """A file that cannot be read as Google Benchmark JSON; the message names the file."""


def read(path):
    """The parsed JSON of a file, whatever its structure (for a validator: structure_problems)."""
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except OSError as e:
        raise GBenchError(f"{path}: cannot read: {e.strerror or e}")
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise GBenchError(f"{path}: not valid JSON ({e})")


def load(path):
    """The parsed JSON of a Google Benchmark output file (a dict with a "benchmarks" list)."""
    data = read(path)
    if not isinstance(data, dict) or not isinstance(data.get("benchmarks"), list):
        raise GBenchError(f'{path}: not Google Benchmark JSON (no "benchmarks" array; '
                          "write it with --benchmark_out=FILE --benchmark_out_format=json)")
    return data


def structure_problems(data):
    """(problems, rows) of parsed JSON: what is wrong with its top level, "context" and
    "benchmarks" (empty when nothing is), and the "benchmarks" list ([] when there is none)."""
    if not isinstance(data, dict):
        return ["top level is not a JSON object"], []
    problems = []
    if not isinstance(data.get("context"), dict):
        problems.append('missing or malformed "context" object')
    rows = data.get("benchmarks")
    if not isinstance(rows, list):
        problems.append('missing or malformed "benchmarks" array')
        return problems, []
    if not rows:
        problems.append('"benchmarks" is empty: nothing was run')
    return problems, rows


def aggregate_of(row):
    """The aggregate's name ("median", ...) for an aggregate row, else None. A row is an
    aggregate by its run_type or aggregate_name, or (older files) by its name's suffix."""
    if row.get("aggregate_name"):
        return row["aggregate_name"]
    m = AGGREGATE_RE.search(row.get("name", ""))
    if m:
        return m.group("aggregate")
    return "aggregate" if row.get("run_type") == "aggregate" else None


def base_name(name):
    """The benchmark's identity: the name without Google Benchmark's suffixes."""
    name = AGGREGATE_RE.sub("", name)
    while True:
        stripped = SUFFIX_RE.sub("", name)
        if stripped == name:
            return name
        name = stripped


def parse_quadrant_name(name):
    """(scene, engine, n, threads) of a quadrant_bench row's name, or None."""
    m = QUADRANT_NAME_RE.match(base_name(name or ""))
    if not m:
        return None
    return m.group("scene"), m.group("engine"), int(m.group("n")), int(m.group("threads"))


class Rows:
    """A file's rows by base name: per-repetition rows, _median aggregates, failures."""

    def __init__(self, data, where="", strict=False):
        self.reps = {}      # name -> [rows], in file order
        self.medians = {}   # name -> the _median aggregate row
        self.failed = {}    # name -> error message
        self.failed_rows = []  # (the row's full name, error message) of every failed row, in file order
        self.order = []     # every base name, in the order of its first row (any kind of row)
        seen = set()
        for i, row in enumerate(data.get("benchmarks", []) if isinstance(data, dict) else []):
            if not isinstance(row, dict) or not isinstance(row.get("name"), str):
                if strict:
                    raise GBenchError(f"{where}: benchmarks[{i}] is not a benchmark row (no name)")
                continue
            name = base_name(row.get("run_name") or row["name"])
            if name not in seen:
                seen.add(name)
                self.order.append(name)
            if row.get("error_occurred"):
                self.failed[name] = row.get("error_message", "no message")
                self.failed_rows.append((row["name"], row.get("error_message", "")))
                continue
            aggregate = aggregate_of(row)
            if aggregate:
                if aggregate == "median":
                    self.medians[name] = row
                continue
            self.reps.setdefault(name, []).append(row)


def ms_per_step(row):
    """The row's milliseconds per step: the ms_per_step counter, else real_time / steps; or None."""
    ms = row.get("ms_per_step")
    if isinstance(ms, (int, float)):
        return float(ms)
    unit = TIME_UNITS_S.get(row.get("time_unit", "ns"))
    real, steps = row.get("real_time"), row.get("steps", 1)
    if unit is None or not isinstance(real, (int, float)) or not isinstance(steps, (int, float)) or steps <= 0:
        return None
    return real * unit * 1e3 / steps


# ---- Machine load ------------------------------------------------------------------------------
# Whether a run's timings were taken on a loaded machine: the one rule, used by bench_report.py
# (noise flags) and compare.py (no verdict from a loaded side, issue #29 item 4).

# Other processes using more than this many cores during a repetition (beyond the run's own
# --busy loops) make that benchmark's figures suspect (counter others_cpu: CPU time of every
# process but the suite's, over the repetition's setup, warm-up and timed steps).
OTHERS_LIMIT = 0.5


def context_cores(context):
    """The machine's core count from a context ("cores", else "num_cpus"), or None."""
    for key in ("cores", "num_cpus"):
        try:
            v = int((context or {}).get(key))
            if v > 0:
                return v
        except (TypeError, ValueError):
            pass
    return None


def busy_processes(context):
    """The run's own busy loops (tools/quadrant bench --busy K), 0 if none or unknown."""
    try:
        return int((context or {}).get("busy_processes", 0))
    except (TypeError, ValueError):
        return 0


def run_load_problems(context):
    """Reasons (strings) why a whole run was loaded: the 1-minute load average before it started
    (context load_avg_before, read by tools/quadrant before any busy loop) above the core count.
    The load average during the run is not the test: it counts the run's own threads."""
    try:
        before = float((context or {}).get("load_avg_before"))
    except (TypeError, ValueError):
        return []
    cores = context_cores(context)
    if cores and before > cores:
        return [f"load average {before:.2f} before the run, above the {cores} cores"]
    return []


def others_cpu_excess(row, busy=0):
    """Cores' worth of CPU other processes used during the row's repetition beyond the run's own
    busy loops, or None where the row does not say (counter others_cpu)."""
    v = row.get("others_cpu")
    if not isinstance(v, (int, float)):
        return None
    return float(v) - busy
