#!/usr/bin/env python3
"""distributed.json and distributed.md from quadrant_distributed's runs (one JSON object a line).

Usage: distributed_report.py RUNS.jsonl --machine M --commit C --load L --json OUT.json --md OUT.md

distributed.json: {"context": {...}, "runs": [{"scene", "ranks", "bodies", "ms_per_step",
"rounds_per_step", "bytes_per_step", "shadow_fraction", "imbalance", "state_hash", "stage_ms":
{stage: [mean over ranks, slowest rank] ms a step}, ...}]}.
distributed.md: one table per solver and kind of run (weak scaling, strong scaling per scene)
with the weak-scaling efficiency (1-rank ms / R-rank ms at equal bodies per rank) and the
strong-scaling speed-up, the pyramid's apex drift where measured, and under each a per-stage
profile of the step; runs with "independent" (R one-rank worlds side by side, no rank waiting for
another) give the weak-scaling tables' machine ceiling (1-rank ms / their ms) and how much of it
the distributed run keeps; oversubscribed rows (more ranks than cores) are marked. With the jacobi
solver, rows whose state hash differs from the 1-rank run of the same scene and size are flagged
(they must not exist); soft_step's hashes depend on the rank count by design. Repeated runs of
one configuration ("repetition": bench --ranks --repetitions) make one row: the median run (the
lower middle for an even count), its range, and efficiencies and ratios as the medians of each
repetition's own (1-rank and R-rank runs of the same repetition).
"""
import argparse
import json
import statistics
import sys


def collapse(runs):
    """One row per configuration: the run of median ms per step, with "repetitions", "ms_range"
    and "ms_by_repetition" (repetition -> ms); with --world, "world_ratio", the median of the
    runs' own ms / world ms."""
    by = {}
    for r in runs:
        key = (r.get("solver", "jacobi"), bool(r.get("weak")), r["scene"], r["bodies"], r["ranks"],
               r.get("threads", 1), bool(r.get("independent")))
        by.setdefault(key, []).append(r)
    rows = []
    for rs in by.values():
        rs = sorted(rs, key=lambda r: r["ms_per_step"])
        row = dict(rs[(len(rs) - 1) // 2])
        row["repetitions"] = len(rs)
        row["ms_range"] = [rs[0]["ms_per_step"], rs[-1]["ms_per_step"]]
        row["ms_by_repetition"] = {r["repetition"]: r["ms_per_step"] for r in rs if "repetition" in r}
        ratios = [r["ms_per_step"] / r["world_ms_per_step"] for r in rs if r.get("world_ms_per_step", 0) > 0]
        if ratios:
            row["world_ratio"] = statistics.median(ratios)
            row["world_ms_per_step"] = statistics.median(r["world_ms_per_step"] for r in rs if r.get("world_ms_per_step", 0) > 0)
        rows.append(row)
    return rows


def paired(a, b):
    """The median over the repetitions both rows have of a's ms / b's ms (a time ratio)."""
    common = sorted(set(a["ms_by_repetition"]) & set(b["ms_by_repetition"]))
    if not common:
        return a["ms_per_step"] / b["ms_per_step"] if b["ms_per_step"] > 0 else 0.0
    return statistics.median(a["ms_by_repetition"][i] / b["ms_by_repetition"][i] for i in common
                             if b["ms_by_repetition"][i] > 0)


def ms_cell(r):
    lo, hi = r["ms_range"]
    return f"{r['ms_per_step']:.2f}" + (f" ({lo:.2f}-{hi:.2f})" if r["repetitions"] > 1 else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs")
    ap.add_argument("--machine", required=True)
    ap.add_argument("--commit", required=True)
    ap.add_argument("--load", default="unknown")
    ap.add_argument("--json", required=True)
    ap.add_argument("--md", required=True)
    ap.add_argument("--png", help="also draw ms per step against ranks, one line per kind of run")
    args = ap.parse_args()
    runs = []
    with open(args.runs) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                runs.append(json.loads(line))
            except json.JSONDecodeError as e:
                sys.exit(f"distributed_report: {args.runs}:{number}: not JSON ({e})")
    if not runs:
        sys.exit("distributed_report: no runs")
    context = {"machine": args.machine, "commit": args.commit, "load_before": args.load,
               "solver": "soft_step: the World's default engine inside each rank; jacobi: the same bits on any rank count",
               "ms_per_step": "slowest rank's wall time over the timed steps",
               "imbalance": "max / mean over ranks of owned bodies plus their contacts, averaged over the steps"}
    with open(args.json, "w") as f:
        json.dump({"context": context, "runs": runs}, f, indent=1)
        f.write("\n")

    groups = {}
    # R independent one-rank worlds side by side, by (solver, scene, R): the machine's ceiling.
    alone = {}
    runs = collapse(runs)
    repeated = max(r["repetitions"] for r in runs) > 1
    for r in runs:
        if r.get("independent"):
            alone[(r.get("solver", "jacobi"), r["scene"], r["ranks"])] = r
    for r in runs:
        if r.get("independent"):
            continue
        # Strong-scaling runs of one scene at different sizes (the 1,000,000-body run beside the
        # 64000-body series) are separate series: their hashes and times are not comparable.
        weak = bool(r.get("weak"))
        solver = r.get("solver", "jacobi")
        groups.setdefault((solver, "weak" if weak else "strong", r["scene"], 0 if weak else r["bodies"]), []).append(r)
    out = [f"# The distributed world (MPI)\n",
           f"Machine {args.machine}, commit {args.commit}, load average before the runs {args.load}. "
           "Solvers: `soft_step`, the default (`WorldDef::solver`): the World's soft step inside each rank at its default "
           "budget, the boundary bodies' solver states exchanged between its passes (state hashes depend on the rank count; "
           "on one rank they are the World's); `jacobi`, the deterministic option: the same state hashes on any rank count, "
           "equal to the single-process World's with the same solver. "
           "`*`: more ranks than cores (oversubscribed). Imbalance: max / mean over the ranks of owned bodies plus their contacts (a work count). "
           "Apex drift: the pyramid's apex from its pose after the warm-up (1 s) to the end of the run, the largest of samples every 0.5 s. "
           "Ceiling (weak scaling): the 1-rank time over that of as many independent one-rank processes side by side "
           "(`quadrant_distributed --independent`: the same work per process, nobody waits), what the machine's shared "
           "caches, memory and clocks leave; of ceiling: the efficiency over the ceiling."
           + (f" Every configuration ran {max(r['repetitions'] for r in runs)} times, the rank counts in turn: ms/step is the median "
              "(range in brackets); efficiencies, speed-ups, ceilings and ratios are medians of each repetition's own."
              if repeated else "") + "\n"]
    order = lambda g: (g[0][0] != "soft_step", g[0][1] != "weak", g[0][2], g[0][3])
    for (solver, kind, scene, _), rows in sorted(groups.items(), key=order):
        rows.sort(key=lambda r: (r["ranks"], -r.get("threads", 1)))
        base = rows[0]
        if kind == "weak":
            out.append(f"\n## {solver}: weak scaling, {scene}, {base['bodies'] // base['ranks']} bodies per rank\n")
            out.append("| ranks | bodies | ms/step | efficiency | rounds/step | bytes/step | bytes/boundary body | shadow fraction | imbalance | peak MB (all ranks) | state hash |")
            ceiling = any((solver, scene, r["ranks"]) in alone for r in rows)
        else:
            budget = f"{base['iterations']} iterations" if solver == "jacobi" else "default budget"
            out.append(f"\n## {solver}: strong scaling, {scene}, {base['bodies']} bodies, {budget}\n")
            out.append("| ranks | bodies | ms/step | speed-up | rounds/step | bytes/step | bytes/boundary body | shadow fraction | imbalance | peak MB (all ranks) | state hash |")
            ceiling = False
        drift = any("apex_drift_m" in r for r in rows)
        # Ranks x threads (the lent 16-core machine's runs, tools/device_distributed.sh): a column
        # for the threads inside each rank wherever a row has more than one.
        threaded = any(r.get("threads", 1) > 1 for r in rows)
        if threaded:
            out[-1] = out[-1].replace("| ranks |", "| ranks | threads |", 1)
        if drift:
            out[-1] += " apex drift (m) |"
        if ceiling:
            out[-1] += " independent ms/step | ceiling | of ceiling |"
        out.append("|---:|" + ("---:|" if threaded else "") + "---:|" * 9 + "---|"
                   + ("---:|" if drift else "") + ("---:|" * 3 if ceiling else ""))
        for r in rows:
            ratio = paired(base, r)
            ranks = f"{r['ranks']}{'*' if r.get('oversubscribed') else ''}"
            figure = f"{100 * ratio:.0f} %" if kind == "weak" else f"{ratio:.2f}"
            same = "" if kind == "weak" or solver != "jacobi" or r["state_hash"] == base["state_hash"] else " (differs!)"
            if threaded:
                ranks += f" | {r.get('threads', 1)}"
            line = (f"| {ranks} | {r['bodies']} | {ms_cell(r)} | {figure} | {r['rounds_per_step']} | "
                    f"{r['bytes_per_step']:.0f} | {r['bytes_per_boundary_body']:.0f} | {r['shadow_fraction']:.4f} | "
                    f"{r['imbalance']:.3f} | {r.get('peak_rss_mb', 0):.0f} | `{r['state_hash']}`{same} |")
            if drift:
                line += f" {r['apex_drift_m']:.4f} |" if "apex_drift_m" in r else " |"
            if ceiling:
                a = alone.get((solver, scene, r["ranks"]))
                if a and a["ms_per_step"] > 0 and r["ms_per_step"] > 0:
                    line += (f" {ms_cell(a)} | {100 * paired(base, a):.0f} % | "
                             f"{100 * paired(a, r):.0f} % |")
                else:
                    line += " | | |"
            out.append(line)
        # One rank against the single-process World's default engine on the same scene (the run
        # with --world): issue #30 asks for at most 1.5x.
        for r in rows:
            if "world_ms_per_step" in r and r["world_ms_per_step"] > 0:
                out.append(f"\nOne rank against `World` (its default engine, soft_step, one thread, the same bodies and "
                           f"steps, timed after the distributed run): {r['ms_per_step']:.2f} ms against "
                           f"{r['world_ms_per_step']:.2f} ms a step, {r.get('world_ratio', r['ms_per_step'] / r['world_ms_per_step']):.2f}x"
                           + (" (medians)." if r["repetitions"] > 1 else "."))
        # Where the step went, stage by stage (DistributedStats): the slowest rank's ms a step
        # (the mean over the ranks in brackets where they differ). wait is part of the rounds'
        # stages (migrate, shadows, exchange), not a stage of its own.
        if all("stage_ms" in r for r in rows):
            names = list(rows[0]["stage_ms"].keys())
            out.append("\nWhere the step went (ms a step, slowest rank; mean over ranks in brackets; "
                       "`wait`: the part of the rounds and of the halo's reduction spent in MPI receive and completion):\n")
            out.append("| ranks | " + " | ".join(names) + " |")
            out.append("|---:|" + "---:|" * len(names))
            for r in rows:
                cells = []
                for n in names:
                    mean, most = r["stage_ms"][n]
                    cells.append(f"{most:.3f}" + (f" ({mean:.3f})" if abs(most - mean) > 0.0005 else ""))
                out.append(f"| {r['ranks']}{'*' if r.get('oversubscribed') else ''} | " + " | ".join(cells) + " |")
    with open(args.md, "w") as f:
        f.write("\n".join(out) + "\n")
    if args.png:
        plot(groups, args)


def plot(groups, args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (solver, kind, scene, _), rows in sorted(groups.items(), key=lambda g: (g[0][0] != "soft_step", g[0][1] != "weak", g[0][2], g[0][3])):
        rows = sorted(rows, key=lambda r: r["ranks"])  # the independent runs are in the table only
        if len(rows) < 2:
            continue  # a single point (the 1,000,000-body run) is in the table
        size = f"{rows[0]['bodies'] // rows[0]['ranks']} per rank" if kind == "weak" else f"{rows[0]['bodies']} bodies"
        ax.plot([r["ranks"] for r in rows], [r["ms_per_step"] for r in rows], marker="o" if solver == "soft_step" else "s",
                linestyle="-" if solver == "soft_step" else "--", label=f"{solver}: {kind}, {scene}, {size}")
        for r in rows:
            if r.get("oversubscribed"):
                ax.annotate("*", (r["ranks"], r["ms_per_step"]), textcoords="offset points", xytext=(4, 4))
    ax.set_xlabel("ranks (* oversubscribed)")
    ax.set_ylabel("ms per step (slowest rank)")
    ax.set_yscale("log")
    ax.set_xticks(sorted({r["ranks"] for rows in groups.values() for r in rows}))
    ax.set_title(f"Quadrant distributed world, {args.machine}, {args.commit}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.png, dpi=120)


if __name__ == "__main__":
    main()
