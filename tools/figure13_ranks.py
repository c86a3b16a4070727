#!/usr/bin/env python3
"""The thesis's Figure 13 for the distributed world: circles coloured by the MPI rank that owns
them, with the tile grid and each tile's owner (quadrant_distributed --owners CSV).

usage: figure13_ranks.py IN.csv OUT.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle, Rectangle  # noqa: E402

COLORS = ["#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1]) as f:
        head = f.readline().lstrip("# ").split()
        x0, y0, x1, y1 = (float(v) for v in head[1:5])
        tx, ty, ranks, steps = int(head[6]), int(head[7]), int(head[9]), int(head[11])
        owners = [int(v) for v in head[13:]]
        bodies = [(float(r["x"]), float(r["y"]), float(r["radius"]), int(r["rank"])) for r in csv.DictReader(f)]
    if len(owners) != tx * ty:
        sys.exit(f"figure13_ranks: {argv[1]}: {len(owners)} tile owners for {tx} x {ty} tiles")
    fig, ax = plt.subplots(figsize=(9, 9), dpi=110)
    w, h = (x1 - x0) / tx, (y1 - y0) / ty
    for t, o in enumerate(owners):
        ax.add_patch(Rectangle((x0 + (t % tx) * w, y0 + (t // tx) * h), w, h, facecolor=COLORS[o % len(COLORS)],
                               alpha=0.08, edgecolor="#999999", lw=0.4))
    for rank in range(ranks):
        patches = [Circle((b[0], b[1]), b[2]) for b in bodies if b[3] == rank]
        ax.add_collection(PatchCollection(patches, facecolor=COLORS[rank % len(COLORS)], edgecolor="none"))
        ax.plot([], [], "o", color=COLORS[rank % len(COLORS)], label=f"rank {rank}: {len(patches)}")
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{len(bodies)} circles after {steps} steps; colour = owning MPI rank, tiles tinted by owner\n"
                 f"(the thesis's Figure 13 for Quadrant's distributed world, {ranks} ranks, {tx} x {ty} tiles)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=4, fontsize=8, frameon=False)
    fig.savefig(argv[2], bbox_inches="tight")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
