#!/usr/bin/python3
"""Performance history: one row per benchmark per recorded run, and a plot of it.

Usage (Debian's interpreter, /usr/bin/python3, which sees python3-matplotlib):

    /usr/bin/python3 tools/history.py record BENCH_JSON [--machine M] [--csv results/history.csv]
                                                        [--png results/history.png]
        appends the run's per-benchmark medians to the CSV (created with a header if missing)
        and redraws the plot
    /usr/bin/python3 tools/history.py plot [--csv ...] [--png ...]
        only redraws the plot

CSV columns: record (1, 2, ... one number per recorded run), date (UTC, ISO 8601, of the run),
commit, machine, benchmark, steps_per_second and ms_per_step (medians over the run's
repetitions), repetitions. The plot: one line per benchmark (per machine and benchmark when the
file holds several machines), x = record number labelled with the short commit, y = median ms
per step (log scale when the lines span more than a factor 10, as 1000 and 16000 bodies do).
"""

import argparse
import csv
import datetime
import os
import re
import statistics
import sys

import gbench_json
import plot_style

FIELDS = ["record", "date", "commit", "machine", "benchmark", "steps_per_second", "ms_per_step",
          "repetitions"]


class HistoryError(Exception):
    pass


def natural_key(text):
    """Sorts n:4000 before n:16000."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", text)]


def load_run(path):
    try:
        return gbench_json.load(path)
    except gbench_json.GBenchError as e:
        raise HistoryError(str(e))


def run_date_utc(context):
    """The run's date (Google Benchmark writes local time with an offset) in UTC; now if absent."""
    text = context.get("date", "")
    try:
        when = datetime.datetime.fromisoformat(text)
        if when.tzinfo is None:
            raise ValueError("no offset")
    except (TypeError, ValueError):
        when = datetime.datetime.now(datetime.timezone.utc)
    return when.astimezone(datetime.timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def medians(data):
    """{benchmark: (steps_per_second, ms_per_step, repetitions)} from the per-repetition rows."""
    per = {}
    for name, rows in gbench_json.Rows(data).reps.items():
        for row in rows:
            ms = gbench_json.ms_per_step(row)
            if ms is None:
                continue
            sps = row.get("steps_per_second")
            if not isinstance(sps, (int, float)):
                sps = 1e3 / ms if ms > 0 else float("nan")
            per.setdefault(name, []).append((float(sps), float(ms)))
    return {name: (statistics.median(v[0] for v in values), statistics.median(v[1] for v in values),
                   len(values))
            for name, values in per.items()}


def read_history(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames != FIELDS:
            raise HistoryError(f"{path}: unexpected header {reader.fieldnames} (expected {FIELDS})")
        return list(reader)


def record(json_path, csv_path, machine):
    data = load_run(json_path)
    context = data.get("context", {}) if isinstance(data.get("context"), dict) else {}
    meds = medians(data)
    if not meds:
        raise HistoryError(f"{json_path}: no successful per-repetition rows to record")
    rows = read_history(csv_path)
    index = max((int(r["record"]) for r in rows), default=0) + 1
    commit = str(context.get("commit", "unknown"))
    machine = machine or str(context.get("machine", "unknown"))
    date = run_date_utc(context)
    new_file = not os.path.exists(csv_path)
    os.makedirs(os.path.dirname(os.path.abspath(csv_path)), exist_ok=True)
    with open(csv_path, "a", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS, lineterminator="\n")
        if new_file:
            writer.writeheader()
        for name in sorted(meds, key=natural_key):
            sps, ms, reps = meds[name]
            writer.writerow({"record": index, "date": date, "commit": commit, "machine": machine,
                             "benchmark": name, "steps_per_second": f"{sps:.6g}",
                             "ms_per_step": f"{ms:.6g}", "repetitions": reps})
    print(f"history: record {index} ({len(meds)} benchmarks, commit {commit}, machine {machine}) "
          f"appended to {csv_path}", file=sys.stderr)


def plot(csv_path, png_path):
    rows = read_history(csv_path)
    if not rows:
        raise HistoryError(f"{csv_path}: no history to plot")
    import matplotlib
    matplotlib.use("Agg")  # no display: files only
    import matplotlib.pyplot as plt

    machines = sorted({r["machine"] for r in rows})
    lines = {}
    commits = {}
    for r in rows:
        key = r["benchmark"] if len(machines) == 1 else f"{r['machine']}: {r['benchmark']}"
        lines.setdefault(key, []).append((int(r["record"]), float(r["ms_per_step"])))
        commits[int(r["record"])] = r["commit"][:12]
    fig, ax = plt.subplots(figsize=(10, 6))
    # The engine's colour of every figure (plot_style.py); scenes by line style, sizes by marker.
    scenes, counts = [], []
    for key in lines:
        parsed = gbench_json.parse_quadrant_name(key.split(": ")[-1])
        if parsed and parsed[0] not in scenes:
            scenes.append(parsed[0])
        if parsed and parsed[2] not in counts:
            counts.append(parsed[2])
    counts.sort()
    for key in sorted(lines, key=natural_key):
        pts = sorted(lines[key])
        parsed = gbench_json.parse_quadrant_name(key.split(": ")[-1])
        colour, marker, linestyle = None, "o", "-"
        if parsed:
            colour = plot_style.style(parsed[1])[0]
            marker = "osD^vP"[counts.index(parsed[2]) % 6]
            linestyle = ["-", "--", "-.", ":"][scenes.index(parsed[0]) % 4]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, linestyle=linestyle, color=colour,
                label=key)
    records = sorted(commits)
    ax.set_xticks(records)
    ax.set_xticklabels([f"{i}\n{commits[i]}" for i in records], fontsize=8,
                       rotation=0 if len(records) <= 12 else 90)
    values = [p[1] for pts in lines.values() for p in pts if p[1] > 0]
    if values and max(values) / min(values) > 10:
        ax.set_yscale("log")
        # Readable ticks (1, 2, 5, 10, ...) instead of bare powers of ten.
        from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter
        ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("record (commit)")
    ax.set_ylabel("ms per step (median over repetitions)")
    ax.set_title("Quadrant benchmark history" + (f" ({machines[0]})" if len(machines) == 1 else ""))
    ax.grid(True, alpha=0.3)
    if len(lines) <= 16:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        # A full sweep has 100+ benchmarks: what the colours, line styles and markers mean instead.
        engines = sorted({p[1] for p in (gbench_json.parse_quadrant_name(k.split(": ")[-1]) for k in lines) if p})
        handles = [plt.Line2D([], [], color=plot_style.style(e)[0], label=plot_style.style(e)[2]) for e in engines]
        handles += [plt.Line2D([], [], color="black", linestyle=["-", "--", "-.", ":"][i % 4], label=sc)
                    for i, sc in enumerate(scenes)]
        handles += [plt.Line2D([], [], color="black", linestyle="", marker="osD^vP"[i % 6], label=f"N = {n}")
                    for i, n in enumerate(counts)]
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  title=f"{len(lines)} benchmarks (thread counts share a style)", title_fontsize=7)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(png_path)), exist_ok=True)
    fig.savefig(png_path, dpi=110)
    plt.close(fig)
    print(f"history: plot written to {png_path}", file=sys.stderr)


def main(argv=None):
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(prog="history.py", description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    rec = sub.add_parser("record", help="append a run's medians and redraw the plot")
    rec.add_argument("json", help="Google Benchmark JSON of the run (quadrant_bench output)")
    rec.add_argument("--machine", default="", help="machine name (default: the JSON context's)")
    plo = sub.add_parser("plot", help="redraw the plot")
    for p in (rec, plo):
        p.add_argument("--csv", default=os.path.join(root, "results", "history.csv"))
        p.add_argument("--png", default=os.path.join(root, "results", "history.png"))
    args = parser.parse_args(argv)
    try:
        if args.command == "record":
            record(args.json, args.csv, args.machine)
        plot(args.csv, args.png)
    except HistoryError as e:
        print(f"history: error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
