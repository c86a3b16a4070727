#!/usr/bin/env python3
"""Draws the thesis's Figure 13 from quadrant_figure13's CSV: the circles coloured by the thread
that owns them (grey: the master, for bodies straddling a boundary) and the region quad-tree,
each node subdivided while it holds bodies, as in the thesis's picture.

usage: figure13.py IN.csv OUT.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

COLORS = ["#d62728", "#1f77b4", "#2ca02c", "#ff7f0e"]  # threads 0..3
MAX_DEPTH = 6


def read(path):
    region, bodies = None, []
    with open(path) as f:
        first = f.readline()
        parts = first.replace(",", " ").split()
        region = tuple(float(v) for v in parts[2:6])
        for row in csv.DictReader(f):
            if int(row["dynamic"]):
                bodies.append((float(row["x"]), float(row["y"]), float(row["radius"]), int(row["owner"])))
    # "# region x0 y0 x1 y1, 5000 bodies after 120 steps, ...": the part after the region.
    header = first.lstrip("# ").split(",", 1)[1].strip() if "," in first else ""
    return region, bodies, header


def quad_tree_nodes(x0, y0, size, bodies, depth, out):
    """Node outlines: a node is split while a child can wholly contain one of its bodies."""
    out.append((x0, y0, size))
    if depth == MAX_DEPTH or not bodies:
        return
    half = size / 2
    for cx in (0, 1):
        for cy in (0, 1):
            lx, ly = x0 + cx * half, y0 + cy * half
            inside = [b for b in bodies if lx <= b[0] - b[2] and b[0] + b[2] <= lx + half
                      and ly <= b[1] - b[2] and b[1] + b[2] <= ly + half]
            if inside:
                quad_tree_nodes(lx, ly, half, inside, depth + 1, out)


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    (x0, y0, x1, y1), bodies, header = read(argv[1])
    size = max(x1 - x0, y1 - y0)
    fig, ax = plt.subplots(figsize=(9, 9), dpi=110)
    nodes = []
    quad_tree_nodes(x0, y0, size, bodies, 0, nodes)
    for nx, ny, ns in nodes:
        ax.add_patch(Rectangle((nx, ny), ns, ns, fill=False, lw=0.4, ec="#999999"))
    for owner in sorted({b[3] for b in bodies}):
        color = COLORS[owner % len(COLORS)] if owner >= 0 else "#555555"
        patches = [Circle((b[0], b[1]), b[2]) for b in bodies if b[3] == owner]
        ax.add_collection(PatchCollection(patches, facecolor=color, edgecolor="none"))
        label = f"thread {owner}" if owner >= 0 else "master (straddles a boundary)"
        ax.plot([], [], "o", color=color, label=f"{label}: {len(patches)}")
    ax.plot([x0 + size / 2] * 2, [y0, y0 + size], color="black", lw=1.2)
    ax.plot([x0, x0 + size], [y0 + size / 2] * 2, color="black", lw=1.2)
    ax.set_xlim(x0, x0 + size)
    ax.set_ylim(y0, y0 + size)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{len(bodies)}-circle stress test with the quad-tree drawn; colour = owning thread\n"
                 "(the thesis's Figure 13, Quadrant's quadrants scheme, 4 threads)")
    # Below the square, not over it: the legend covered bodies in the upper-right quadrant.
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=3, fontsize=8, frameon=False)
    fig.text(0.01, 0.005, f"{header}. Split square {size:.1f} m x {size:.1f} m (black lines: the four "
             f"threads' quadrants); grey squares: quad-tree nodes holding bodies, to depth {MAX_DEPTH}.",
             fontsize=6.5, ha="left", va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    fig.savefig(argv[2])
    print(f"figure13: wrote {argv[2]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
