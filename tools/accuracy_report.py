#!/usr/bin/python3
"""What accuracy costs in time: checks, merges and reports quadrant_accuracy's JSON.

    accuracy_report.py check accuracy.json          structure check (exit 1 with the problems)
    accuracy_report.py check-effects effects.json   the same for quadrant_effects' JSON
    accuracy_report.py merge accuracy.json OTHER.json
                                                    appends OTHER's runs and hard cases (e.g. the
                                                    double-precision build's) to accuracy.json
    accuracy_report.py report accuracy.json --out DIR
                                                    writes DIR/accuracy.md and DIR/accuracy.png

Run with Debian's /usr/bin/python3 (python3-matplotlib; Agg backend, no display needed).
"""
import argparse
import json
import math
import os
import sys

import plot_style  # one colour per engine in every figure

PILES = ["vertical_stack", "pyramid", "mass_ratio_100", "mass_ratio_400", "tall_stack", "heavy_on_supports",
         "heavy_on_slab"]
STRESS = ["circle_stress", "polygon_stress"]

# Per scene kind: the error columns of the tables (JSON name, heading, format) and the error the
# plot's first row puts against time. Piles: the largest displacement of any body from where it
# was spawned, at the end (a standing pile: millimetres to centimetres; a fallen one: metres).
# Stress scenes: |kinetic energy drift| (restitution 1 everywhere: it should stay 0).
PILE_COLUMNS = [
    ("max_penetration_m", "max pen. (m)", "{:.3g}"),
    ("mean_penetration_m", "mean pen. (m)", "{:.3g}"),
    ("top_drift_m", "top drift 1 s..end (m)", "{:.3g}"),
    ("max_drift_m", "max drift 1 s..end (m)", "{:.3g}"),
    ("max_displacement_m", "max displ. from spawn (m)", "{:.3g}"),
    ("fall_time_s", "fell at (s)", "{:.2f}"),
]
STRESS_COLUMNS = [
    ("max_penetration_m", "max pen. (m)", "{:.3g}"),
    ("mean_penetration_m", "mean pen. (m)", "{:.3g}"),
    ("ke_drift", "KE drift", "{:+.3g}"),
    ("momentum_change_rel", "momentum change (rel.)", "{:.3g}"),
    ("tunnelled", "tunnelled", "{:.0f}"),
]
PRIMARY = {"pile": ("max_displacement_m", "largest displacement from spawn at the end (m)"),
           "stress": ("ke_drift", "|kinetic energy drift| over the run")}
FLOOR = 1e-6  # log axes: smaller errors (and exact zeros) are drawn at this floor


def kind(scene):
    return "stress" if scene in STRESS else "pile"


def label(run):
    """Short id for tables and plot labels: the setting id, plus the precision when not float."""
    text = run.get("id") or "{}:{}".format(run["engine"], run["setting"])
    return text + (" (double)" if run.get("precision", "float") != "float" else "")


def short(run):
    """A compact plot label."""
    text = (run.get("id") or run["setting"]).replace("quadrant:", "").replace("soft_step+sub", "soft")
    text = text.replace("pgs+it", "pgs").replace("jacobi+it", "jac").replace("box2d:it", "b2d").replace("chipmunk", "chip")
    return text + ("-dbl" if run.get("precision", "float") != "float" else "")


# ---- check ------------------------------------------------------------------------------------

def check_accuracy(data):
    problems = []
    if not isinstance(data, dict):
        return ["top level is not an object"]
    ctx = data.get("context")
    if not isinstance(ctx, dict):
        problems.append("no context object")
    else:
        for key in ("machine", "compiler", "commit", "date", "precision"):
            if not isinstance(ctx.get(key), str):
                problems.append("context.{} missing or not a string".format(key))
    runs = data.get("runs")
    if not isinstance(runs, list) or not runs:
        problems.append("runs missing or empty")
        runs = []
    for i, r in enumerate(runs):
        where = "runs[{}]".format(i)
        if not isinstance(r, dict):
            problems.append(where + " is not an object")
            continue
        for key in ("engine", "solver", "setting", "scene", "precision"):
            if not isinstance(r.get(key), str):
                problems.append("{}.{} missing or not a string".format(where, key))
        if not isinstance(r.get("errors"), dict):
            problems.append(where + ".errors missing or not an object")
            continue
        if "unsupported" in r:
            if r.get("ms_per_step") is not None:
                problems.append(where + " is unsupported but has ms_per_step")
            continue
        ms = r.get("ms_per_step")
        if not isinstance(ms, (int, float)) or not ms > 0:
            problems.append("{}.ms_per_step is not a positive number: {!r}".format(where, ms))
        if "failed" in r:
            continue
        errors = r["errors"]
        if not isinstance(errors.get("finite"), bool):
            problems.append(where + ".errors.finite missing")
        elif errors["finite"]:
            columns = PILE_COLUMNS if kind(r["scene"]) == "pile" else STRESS_COLUMNS
            for key, _, _ in columns:
                if key not in errors:
                    problems.append("{}.errors.{} missing".format(where, key))
                elif errors[key] is not None and not isinstance(errors[key], (int, float)):
                    problems.append("{}.errors.{} is not a number or null".format(where, key))
    hard = data.get("hard_cases")
    if not isinstance(hard, list):
        problems.append("hard_cases missing")
        hard = []
    for i, h in enumerate(hard):
        where = "hard_cases[{}]".format(i)
        if not isinstance(h, dict):
            problems.append(where + " is not an object")
            continue
        for key in ("scene", "engine", "setting"):
            if not isinstance(h.get(key), str):
                problems.append("{}.{} missing or not a string".format(where, key))
        if not isinstance(h.get("pass"), bool):
            problems.append(where + ".pass is not a boolean")
    return problems


def check_effects(data):
    problems = []
    if not isinstance(data, dict):
        return ["top level is not an object"]
    if not isinstance(data.get("context"), dict):
        problems.append("no context object")
    effects = data.get("effects")
    if not isinstance(effects, list) or not effects:
        problems.append("effects missing or empty")
        effects = []
    names = set()
    for i, e in enumerate(effects):
        where = "effects[{}]".format(i)
        if not isinstance(e, dict) or not isinstance(e.get("name"), str) or not isinstance(e.get("scene"), str):
            problems.append(where + " lacks a name or scene")
            continue
        names.add(e["name"])
        for side in ("on_ms", "off_ms"):
            v = e.get(side)
            if v is None:
                # A side may be missing only when the adapter refused it, with the reason.
                if not isinstance(e.get("unsupported"), str) or not e["unsupported"]:
                    problems.append("{}.{} is null without an unsupported reason".format(where, side))
            elif not isinstance(v, (int, float)) or not v > 0:
                problems.append("{}.{} is not a positive number".format(where, side))
    for name in ("gravity", "friction", "restitution", "rotation", "warmStarting", "sleep", "continuous", "damping"):
        if name not in names:
            problems.append("effect {} missing".format(name))
    speedup = data.get("all_off_speedup")
    if not isinstance(speedup, (int, float)) or not speedup > 0:
        problems.append("all_off_speedup is not a positive number: {!r}".format(speedup))
    return problems


# ---- merge ------------------------------------------------------------------------------------

def merge(base_path, other_path):
    with open(base_path) as f:
        base = json.load(f)
    with open(other_path) as f:
        other = json.load(f)
    base["runs"].extend(other.get("runs", []))
    base["hard_cases"].extend(other.get("hard_cases", []))
    ctx = other.get("context", {})
    base["context"].setdefault("merged", []).append(
        {k: ctx.get(k) for k in ("precision", "date", "compiler", "build_type", "repetitions", "steps", "seconds")})
    with open(base_path, "w") as f:
        json.dump(base, f, indent=1)
        f.write("\n")


# ---- report -----------------------------------------------------------------------------------

def fmt(value, spec):
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN"
    return spec.format(value)


def primary_error(run):
    """The plotted error of a run, or None (unsupported, failed, not finite)."""
    if run.get("ms_per_step") is None or "failed" in run or not run["errors"].get("finite", False):
        return None
    value = run["errors"].get(PRIMARY[kind(run["scene"])][0])
    return None if value is None else abs(value)


def pareto(points):
    """Indices of (cost, error) points no other point matches or beats in both (lower is better)."""
    front = []
    for i, (c, e) in enumerate(points):
        dominated = any((c2 <= c and e2 <= e and (c2 < c or e2 < e)) for j, (c2, e2) in enumerate(points) if j != i)
        if not dominated:
            front.append(i)
    return front


def scene_runs(data, scene):
    runs = [r for r in data["runs"] if r["scene"] == scene]
    return sorted(runs, key=lambda r: (r.get("ms_per_step") is None, r.get("ms_per_step") or 0))


def hard_case_section(data, lines):
    hard = data.get("hard_cases", [])
    if not hard:
        return
    cost = {}
    for r in data["runs"]:
        if r.get("ms_per_step") is not None:
            cost[(r["scene"], r.get("id"), r.get("precision", "float"))] = r["ms_per_step"]
    budget = {}
    for h in hard:
        if h["engine"] != "quadrant" and "iterations" in h:
            budget.setdefault(h["scene"], h["iterations"])
    budgets = ", ".join("{} {}".format(scene, n) for scene, n in budget.items())
    lines.append("## The cheapest setting that meets each hard-case criterion\n")
    lines.append("Each hard case (benchmarks/scenes/hard_case_checks.cpp, `RunHardCase`) was run on every swept "
                 "Quadrant setting, whose iteration count (it<N>) replaces the case's own budget, and once on each "
                 "peer at the budget the case gives every engine (its scene's velocity iterations: {}), for "
                 "reference. Cost is the "
                 "setting's median ms per step on the same scene in the sweep above (Box2D at the case's budget "
                 "is the sweep's box2d:it<N>; Bullet and Chipmunk were swept at 8 only). Only float-precision "
                 "Quadrant settings compete for \"cheapest\"; the double build's point is listed for reference.\n"
                 .format(budgets or "no peer ran"))
    lines.append("| hard case | cheapest passing Quadrant setting | its ms/step | criterion |")
    lines.append("|---|---|---|---|")
    scenes = []
    for h in hard:
        if h["scene"] not in scenes:
            scenes.append(h["scene"])
    for scene in scenes:
        rows = [h for h in hard if h["scene"] == scene]
        passing = [h for h in rows if h["pass"] and h["engine"] == "quadrant" and h.get("precision", "float") == "float"
                   and (scene, h.get("id"), "float") in cost]
        passing.sort(key=lambda h: cost[(scene, h.get("id"), "float")])
        criterion = rows[0].get("criterion", "").replace("|", "/")
        if passing:
            best = passing[0]
            ms = cost[(scene, best.get("id"), "float")]
            lines.append("| {} | {} | {:.4f} | {} |".format(scene, best.get("id"), ms, criterion))
        else:
            lines.append("| {} | none of the swept settings passes | - | {} |".format(scene, criterion))
    lines.append("")
    lines.append("Pass (P) or fail (F) per setting (in sweep order), with the setting's ms per step on the "
                 "case's scene:\n")
    ids = []
    for h in hard:
        key = (h.get("id"), h.get("precision", "float"))
        if key not in ids:
            ids.append(key)
    lines.append("| setting | " + " | ".join(scenes) + " |")
    lines.append("|---|" + "---|" * len(scenes))
    for ident, precision in ids:
        cells = []
        for scene in scenes:
            match = [h for h in hard if h["scene"] == scene and h.get("id") == ident
                     and h.get("precision", "float") == precision]
            if not match:
                cells.append("")
                continue
            h = match[0]
            verdict = "unsupported" if "unsupported" in h else ("P" if h["pass"] else "F")
            ms = cost.get((scene, ident, precision))
            cells.append(verdict + (" ({:.3f} ms)".format(ms) if ms is not None else ""))
        name = ident + (" (double)" if precision != "float" else "")
        lines.append("| {} | {} |".format(name, " | ".join(cells)))
    lines.append("")


def report_markdown(data, out, note=""):
    ctx = data["context"]
    scenes = [s for s in PILES + STRESS if any(r["scene"] == s for r in data["runs"])]
    lines = ["# What accuracy costs in time\n"]
    merged = ", ".join("{} ({})".format(m.get("precision"), m.get("date")) for m in ctx.get("merged", []))
    lines.append("Machine `{}`, commit `{}`, {}, compiler {}, {} build, {} precision{}. Written by `tools/quadrant "
                 "accuracy` (benchmarks/accuracy.cpp, tools/accuracy_report.py). One thread per engine; dt = 1/60; "
                 "{} steps per run ({} s); stress scenes at N = {}.{}\n".format(
                     ctx.get("machine"), ctx.get("commit"), ctx.get("date"), ctx.get("compiler"),
                     ctx.get("build_type", "?"), ctx.get("precision"),
                     "; merged points from another build: " + merged if merged else "",
                     ctx.get("steps"), round(ctx.get("steps", 0) / 60.0, 1), ctx.get("stress_count"),
                     " **--quick run: few steps and settings, not a measurement.**" if ctx.get("quick") else ""))
    if note:
        lines.append("**Note**: {}\n".format(note))
    lines.append("**Time**: " + ctx.get("method", "") + " The double-precision point comes from a separate "
                 "binary run after the float sweep, so it is not interleaved with the others.\n")
    lines.append("**Settings**: `quadrant:thesis` (the thesis's one-impulse solver), `quadrant:pgs+itN` (sequential "
                 "impulses, N velocity iterations, 3 position iterations), `quadrant:soft_step+subN` (N sub-steps, "
                 "soft contacts, relax), `quadrant:jacobi+itN` (the distributed world's deterministic solver: Jacobi "
                 "with mass splitting and split impulses, N iterations), `box2d:itN` (Box2D 2.4.1, N velocity and 3 position iterations), `bullet` "
                 "and `chipmunk` at the scenes' 8 iterations. Piles are built with each engine's material mixing, "
                 "so every engine simulates the same friction.\n")
    lines.append("**Errors** (all from the scene API's read-back, never from an engine's own report):\n")
    lines.append("- *max / mean pen.*: overlap depth of body pairs from the read-back poses and the scene's exact "
                 "shapes (circles from centres and radii, polygons by separating axes as the hard cases), sampled "
                 "every {} steps; the mean is over overlapping pairs only. Box2D collides polygons 0.01 m larger "
                 "(its skin), so its piles rest with gaps and show little penetration; a PGS solver lets contacts "
                 "sink by its slop (0.005 m).".format(ctx.get("penetration_sample_every_steps", 6)))
    lines.append("- *top drift*: displacement of the top body (stack top, apex, heavy box, plank) between t = 1 s "
                 "and the end; *max drift*: the largest of any body over the same window; *max displ. from spawn*: "
                 "the largest distance of any body from its spawn pose at the end (catches a pile that fell in "
                 "the first second and then lay still); *fell at*: the first time any body was more than 0.5 m "
                 "from its pose at t = 1 s (before 1 s: from its spawn pose), '-' if never.")
    lines.append("- *KE drift*: kinetic energy at the end over the start, minus 1 (restitution 1 everywhere: an "
                 "exact solver keeps it at 0). *momentum change*: |P_end - P_start| / (sum of m |v| at the start). "
                 "Not a conservation error: the static walls exchange momentum with the bodies, so even an exact "
                 "simulation changes P (by a random-walk amount set by the wall hits); it only flags a setting "
                 "far from the others. *tunnelled*: bodies that were ever entirely past a wall's inner face.\n")
    for scene in scenes:
        k = kind(scene)
        columns = PILE_COLUMNS if k == "pile" else STRESS_COLUMNS
        runs = scene_runs(data, scene)
        bodies = runs[0].get("bodies") if runs else "?"
        lines.append("## {} ({} bodies)\n".format(scene, bodies))
        plotted = [(i, r) for i, r in enumerate(runs)
                   if r.get("ms_per_step") is not None and primary_error(r) is not None]
        front = {plotted[j][0] for j in pareto([(r["ms_per_step"], max(primary_error(r), FLOOR)) for _, r in plotted])}
        lines.append("Ordered by cost; * marks the Pareto front of time against {}.\n".format(PRIMARY[k][1]))
        lines.append("| setting | ms/step | " + " | ".join(c[1] for c in columns) + " | |")
        lines.append("|---|---|" + "---|" * len(columns) + "---|")
        for i, r in enumerate(runs):
            if "unsupported" in r:
                lines.append("| {} | unsupported: {} |".format(label(r), r["unsupported"].replace("|", "/")) +
                             " |" * len(columns) + " |")
                continue
            errors = r["errors"]
            if "failed" in r:
                cells = ["failed: " + r["failed"].replace("|", "/")] + [""] * (len(columns) - 1)
            elif not errors.get("finite", False):
                cells = ["not finite (NaN/inf in the read-back)"] + [""] * (len(columns) - 1)
            else:
                cells = [fmt(errors.get(c[0]), c[2]) for c in columns]
            lines.append("| {} | {} | {} | {} |".format(label(r), fmt(r.get("ms_per_step"), "{:.4f}"),
                                                          " | ".join(cells), "*" if i in front else ""))
        lines.append("")
    hard_case_section(data, lines)
    with open(os.path.join(out, "accuracy.md"), "w") as f:
        f.write("\n".join(lines))


# The engines' colours of every figure (plot_style.py): Box2D is green here as in the FPS plots.
COLOURS = {e: plot_style.style(e)[0] for e in ("quadrant", "box2d", "bullet", "chipmunk")}


def place_labels(ax, points, fontsize=6.5):
    """Labels the points (x, y, text, priority) without overlaps: each label tries four spots
    around its point, in priority order (the Pareto front first), and is left out when all four
    would overlap a label or point already there; accuracy.md lists every setting."""
    fig = ax.figure
    taken = [ax.transData.transform((x, y)) for x, y, _, _ in points]
    taken = [(px - 3, py - 3, px + 3, py + 3) for px, py in taken]  # the markers themselves
    char_w, h = 0.62 * fontsize * fig.dpi / 72, 1.1 * fontsize * fig.dpi / 72
    omitted = 0
    for x, y, text, _ in sorted(points, key=lambda p: p[3]):
        px, py = ax.transData.transform((x, y))
        w = char_w * len(text)
        for dx, dy in ((4, 3), (4, -3 - h), (-4 - w, 3), (-4 - w, -3 - h)):
            box = (px + dx, py + dy, px + dx + w, py + dy + h)
            if all(box[2] < b[0] or box[0] > b[2] or box[3] < b[1] or box[1] > b[3] for b in taken):
                taken.append(box)
                ax.annotate(text, (x, y), fontsize=fontsize, xytext=(dx * 72 / fig.dpi, dy * 72 / fig.dpi),
                            textcoords="offset points")
                break
        else:
            omitted += 1
    return omitted


def report_plot(data, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = [s for s in PILES + STRESS if any(r["scene"] == s for r in data["runs"])]
    cols = min(3, len(scenes))
    nrows = (len(scenes) + cols - 1) // cols
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    fig, axes = plt.subplots(nrows, cols, figsize=(5.2 * cols, 4.3 * nrows), squeeze=False)
    labels = []  # (axes, points to label), placed once the layout is final
    for n, scene in enumerate(scenes):
        ax = axes[n // cols][n % cols]
        runs = [r for r in scene_runs(data, scene) if r.get("ms_per_step") is not None and primary_error(r) is not None]
        pts = [(r["ms_per_step"], max(primary_error(r), FLOOR), r) for r in runs]
        front = set(pareto([(c, e) for c, e, _ in pts]))
        for i, (c, e, r) in enumerate(pts):
            colour = COLOURS.get(r["engine"], "tab:gray")
            marker = "D" if r.get("precision", "float") != "float" else ("s" if r["engine"] != "quadrant" else "o")
            ax.scatter([c], [e], color=colour, marker=marker, s=40 if i in front else 20,
                       edgecolors="black" if i in front else "none", zorder=3)
        labels.append((ax, [(c, e, short(r), 0 if i in front else 1) for i, (c, e, r) in enumerate(pts)]))
        fpts = sorted((pts[i][0], pts[i][1]) for i in front)
        if fpts:
            # The front as a staircase: for any time budget, the best error reachable.
            xs, ys = [fpts[0][0]], [fpts[0][1]]
            for c, e in fpts[1:]:
                xs += [c, c]
                ys += [ys[-1], e]
            ax.plot(xs, ys, color="black", linewidth=0.8, linestyle="--", zorder=2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.grid(True, which="both", linewidth=0.3, alpha=0.5)
        bodies = runs[0].get("bodies") if runs else "?"
        ax.set_title("{} ({} bodies)".format(scene, bodies), fontsize=10)
        ax.set_xlabel("ms per step (1 thread, median)", fontsize=8)
        ax.set_ylabel(PRIMARY[kind(scene)][1], fontsize=8)
        ax.tick_params(labelsize=7)
        # Labels at 1, 2 and 5 per decade where an axis spans at most 3 decades (most panels'
        # time axes span less than one, which had a single label), else one per decade.
        for axis, (lo, hi) in ((ax.xaxis, ax.get_xlim()), (ax.yaxis, ax.get_ylim())):
            wide = lo > 0 and hi / lo > 1e3
            axis.set_major_locator(LogLocator(base=10, subs=(1.0,) if wide else (1.0, 2.0, 5.0)))
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(NullFormatter())
    for n in range(len(scenes), nrows * cols):
        axes[n // cols][n % cols].axis("off")
    handles = [plt.Line2D([], [], color=c, marker="o" if e == "quadrant" else "s", linestyle="", label=e)
               for e, c in COLOURS.items()]
    handles.append(plt.Line2D([], [], color="gray", marker="D", linestyle="", label="double precision"))
    handles.append(plt.Line2D([], [], color="black", linestyle="--", label="Pareto front (outlined points)"))
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=8, frameon=False)
    fig.suptitle("What accuracy costs: time per step against error, one point per setting (lower left is better; "
                 "errors below {:g} drawn at {:g})\n{}, commit {}, {}".format(
                     FLOOR, FLOOR, data["context"].get("machine"), data["context"].get("commit"),
                     data["context"].get("date")), fontsize=9)
    fig.set_dpi(110)
    fig.tight_layout(rect=(0, 0.04, 1, 0.95))
    fig.canvas.draw()  # final axes limits and positions, so labels can avoid each other
    omitted = sum(place_labels(ax, pts) for ax, pts in labels)
    if omitted:
        fig.text(0.99, 0.935, f"{omitted} labels left out where they would overlap (accuracy.md lists every setting)",
                 fontsize=7, ha="right", va="top")
    fig.savefig(os.path.join(out, "accuracy.png"), dpi=110)
    plt.close(fig)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("check")
    p.add_argument("json")
    p = sub.add_parser("check-effects")
    p.add_argument("json")
    p = sub.add_parser("merge")
    p.add_argument("json")
    p.add_argument("other")
    p = sub.add_parser("report")
    p.add_argument("json")
    p.add_argument("--out", required=True)
    p.add_argument("--note", default="", help="a line for the report's header (e.g. why a build is missing)")
    args = parser.parse_args(argv)

    if args.command == "merge":
        merge(args.json, args.other)
        return 0
    with open(args.json) as f:
        data = json.load(f)
    if args.command in ("check", "check-effects"):
        problems = check_accuracy(data) if args.command == "check" else check_effects(data)
        for p in problems:
            print("accuracy_report: {}: {}".format(args.json, p), file=sys.stderr)
        return 1 if problems else 0
    problems = check_accuracy(data)
    if problems:
        for p in problems:
            print("accuracy_report: {}: {}".format(args.json, p), file=sys.stderr)
        return 1
    os.makedirs(args.out, exist_ok=True)
    report_markdown(data, args.out, args.note)
    report_plot(data, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
