#!/usr/bin/python3
"""Plots the random validation campaign (quadrant_validate --random N).

    validation_random_plot.py DIR     reads DIR/validation_random_hits.csv, writes DIR/validation_random.png

Three panels: the p90 difference to Box2D 2.4.1 per class of hit and run (bars; the median and
the maximum as markers), the distribution over all hits of the difference to Box2D (cumulative,
log scale), and the same for the distance from the analytic impact on the single-point hits.
Run with Debian's /usr/bin/python3 (python3-matplotlib; Agg backend, no display needed).
"""
import csv
import math
import os
import sys

FLOOR = 1e-5  # differences below this (float rounding) are drawn at it on the log scales


def quantile(values, q):
    """Nearest-rank quantile, as the C++ report (random_hits.cpp, Distribution)."""
    v = sorted(values)
    return v[max(0, math.ceil(q * len(v)) - 1)]


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__.strip())
    directory = sys.argv[1]
    path = os.path.join(directory, "validation_random_hits.csv")
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"validation_random_plot: cannot read {path}: {e.strerror}")
    if not rows or "analytic:to_box2d" not in rows[0]:
        sys.exit(f"validation_random_plot: {path} is not a campaign's per-hit CSV")

    # Columns "<engine>/<setting>:<quantity>", one triple per run, in run order.
    keys = []
    for column in rows[0].keys():
        if column.endswith(":to_box2d"):
            keys.append(column[: -len(":to_box2d")])

    def label(key):
        if key == "analytic":
            return "analytic impact (single-point hits)"
        engine, _, setting = key.partition("/")
        return engine if setting in ("", "default") else engine + " / " + setting

    runs = [label(k) for k in keys]
    classes = []
    to_box2d, to_analytic = {}, {}
    for r in rows:
        if r["class"] not in classes:
            classes.append(r["class"])
        for key, run in zip(keys, runs):
            if r[key + ":to_box2d"] != "" and not key.startswith("box2d/"):
                to_box2d.setdefault(run, {}).setdefault(r["class"], []).append(float(r[key + ":to_box2d"]))
            if r.get(key + ":to_analytic", "") != "":
                to_analytic.setdefault(run, []).append(float(r[key + ":to_analytic"]))
    order = ["polygon-polygon", "circle-polygon", "circle-circle"]
    classes.sort(key=lambda c: (order.index(c.split(" ")[0]) if c.split(" ")[0] in order else 9, c))
    hits = len(rows)

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    compared = [r for r in runs if r in to_box2d]
    # tab20's dark shades, then its light ones, then tab20b's: the campaign has 21 runs (with
    # Box2D and the analytic impact), and tab20 alone drew the last one as the first.
    tab20 = plt.get_cmap("tab20").colors
    tab20b = plt.get_cmap("tab20b").colors
    colours = list(tab20[0::2]) + list(tab20[1::2]) + list(tab20b[0::4]) + list(tab20b[2::4])
    colour = {run: colours[k % len(colours)] for k, run in enumerate(runs)}
    fig = plt.figure(figsize=(16, 10))
    top = fig.add_subplot(2, 1, 1)
    width = 0.8 / max(1, len(compared))
    for k, run in enumerate(compared):
        xs, p90, med, mx = [], [], [], []
        for i, cls in enumerate(classes):
            v = to_box2d[run].get(cls, [])
            if not v:
                continue
            xs.append(i + (k - (len(compared) - 1) / 2) * width)
            p90.append(max(FLOOR, quantile(v, 0.9)))
            med.append(max(FLOOR, quantile(v, 0.5)))
            mx.append(max(FLOOR, max(v)))
        top.bar(xs, p90, width=width, color=colour[run], label=run)
        top.plot(xs, med, "_", color="black", markersize=6)
        top.plot(xs, mx, "v", color=colour[run], markersize=4, markeredgecolor="black", markeredgewidth=0.4)
    top.axhline(0.05, color="red", linestyle="--", linewidth=1, label="5 %")
    top.axhline(0.01, color="green", linestyle=":", linewidth=1, label="1 %")
    top.set_yscale("log")
    top.set_ylim(FLOOR * 0.8, 10)
    top.set_xticks(range(len(classes)))
    top.set_xticklabels(classes, rotation=15)
    top.set_ylabel("difference to Box2D 2.4.1 / impact speed")
    top.set_title(f"Random campaign, {hits} hits: p90 per class (bars), median (black dash), max (triangle)")
    top.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.005, 1.0))

    for panel, (data, title) in enumerate(
        [
            ({run: [x for c in to_box2d[run].values() for x in c] for run in compared}, "difference to Box2D 2.4.1, all hits"),
            (to_analytic, "distance from the analytic impact, single-point hits"),
        ]
    ):
        ax = fig.add_subplot(2, 2, 3 + panel)
        for run in runs:
            if run not in data or not data[run]:
                continue
            v = sorted(max(FLOOR, x) for x in data[run])
            ax.step(v, [(i + 1) / len(v) for i in range(len(v))], where="post", color=colour[run], label=run)
        ax.axvline(0.05, color="red", linestyle="--", linewidth=1)
        ax.axvline(0.01, color="green", linestyle=":", linewidth=1)
        ax.axhline(0.9, color="grey", linewidth=0.5)
        ax.set_xscale("log")
        ax.set_xlim(FLOOR * 0.8, 10)
        # Two lines: on one, the two panels' labels ran into each other.
        ax.set_xlabel(title + "\n(fraction of impact speed)")
        ax.set_ylabel("fraction of hits at or below")
        # The runs' colours are the top panel's legend; only runs not in it are named here (a
        # legend of all 21 covered the curves).
        extra = [h for h, l in zip(*ax.get_legend_handles_labels()) if l not in compared]
        if extra:
            ax.legend(handles=extra, fontsize=8, loc="lower right")
    fig.tight_layout()
    out = os.path.join(directory, "validation_random.png")
    fig.savefig(out, dpi=90)
    print(f"validation_random_plot: wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
