#!/usr/bin/python3
"""Write results/README.md: the index of the committed results, one table per machine folder.

Usage (Debian's /usr/bin/python3; standard library only):

    /usr/bin/python3 tools/results_index.py           writes results/README.md
    /usr/bin/python3 tools/results_index.py --check   exits 1 if results/README.md does not list
                                                      every file under results/ (or lists one
                                                      that is gone); writes nothing
    tools/quadrant results-index                      the same as the first (the driver also runs
                                                      it after every command that writes into
                                                      results/: --record, --out results/...)

Every file gets what it is (by its name: the program or tools/quadrant command that writes it),
its date and its commit. Date and commit come from the run's own record: the file's JSON context
("date", "commit"; for a report, plot or CSV that a JSON beside it produced, that JSON's), the
last row of history.csv; otherwise the date is the last commit that touched the file (marked
"git"), and a file not yet committed is marked so. A machine folder's description comes from
its JSON contexts (CPU, cores, compiler).

The files are those git tracks or would track under results/ (git ls-files: ignored files such
as results/baselines/ are not listed); outside a git checkout every file under results/ but
baselines/ and failed runs' *.failed-* folders.
"""

import argparse
import datetime
import fnmatch
import json
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
INDEX = "README.md"  # results/README.md, not listed in itself

# (pattern, description, source): pattern is matched against the file's name (fnmatch); the
# description may use {stem} (the '*' part of fps_*.png); source names the JSON beside the file
# whose context gives its date and commit (None: the file's own, if it is JSON).
KINDS = [
    ("bench.json", "Google Benchmark JSON of `tools/quadrant bench` (engines x scenes x sizes x "
     "threads, every repetition): the record the reports below are drawn from; its context holds "
     "the commit, compiler, flags, CPU and settings", None),
    ("bench_busy.json", "the same suite beside K busy processes (`tools/quadrant bench --busy K`)", None),
    ("speedup.md", "steps per second and thread speed-up tables, noise flags and state hashes "
     "(tools/bench_report.py)", "bench.json"),
    ("fps_*.png", "steps per second against bodies and threads, scene `{stem}` (tools/bench_report.py)",
     "bench.json"),
    ("hardcases.json", "the hard cases on Quadrant's default engine and the peers (`tools/quadrant "
     "hardcases`)", None),
    ("hardcases.md", "the hard cases' report: pass or fail per case and engine", "hardcases.json"),
    ("validation.json", "canonical collisions and resting contacts, Quadrant against Box2D and "
     "analytic answers (`tools/quadrant validate`)", None),
    ("validation.md", "the validation's report", "validation.json"),
    ("validation_random.json", "the random campaign of oblique hits (`tools/quadrant validate "
     "--random N`)", None),
    ("validation_random.md", "the random campaign's report", "validation_random.json"),
    ("validation_random.png", "the random campaign's plot (tools/validation_random_plot.py)",
     "validation_random.json"),
    ("validation_random_hits.csv", "every hit of the random campaign", "validation_random.json"),
    ("accuracy.json", "what accuracy costs in time: solvers and iterations against penetration, "
     "drift, energy (`tools/quadrant accuracy`)", None),
    ("accuracy.md", "the accuracy report (tools/accuracy_report.py)", "accuracy.json"),
    ("accuracy.png", "the accuracy plot (tools/accuracy_report.py)", "accuracy.json"),
    ("effects.json", "each effect's cost to Quadrant (`tools/quadrant effects`)", None),
    ("effects.md", "the effects report", "effects.json"),
    ("distributed.json", "the distributed world under MPI: weak and strong scaling "
     "(`tools/quadrant bench --ranks`)", None),
    ("distributed.md", "the distributed runs' report (tools/distributed_report.py)", "distributed.json"),
    ("distributed.png", "ms per step against ranks (tools/distributed_report.py)", "distributed.json"),
    ("figure13_ranks.png", "5000 circles coloured by owning rank, at the largest rank count "
     "(`tools/quadrant bench --ranks`)", "distributed.json"),
    ("figure13_quadtree.png", "the thesis's Figure 13: 5000 circles, quad-tree drawn, coloured by "
     "owning thread (`tools/quadrant figure13`)", None),
    ("queries.json", "world queries (AABB, ray casts) timed against Box2D: quadrant_queries' "
     "Google Benchmark JSON", None),
    ("comparisons.md", "the summaries (compare tables, commands, load) of interleaved comparisons "
     "and busy runs whose raw rounds are not committed", None),
    ("task_overhead.txt", "quadrant_task_overhead's output: one parallel-for's cost per system "
     "and thread count", None),
    ("task_overhead.json", "the pool's and OpenMP's cost per parallel-for and per stage at 1-16 "
     "threads (quadrant_task_overhead's Google Benchmark JSON)", None),
    ("machine.txt", "the machine's nproc / lscpu / uptime at the run (the lent machine's own "
     "description; tools/device_results.py copies it)", "bench.json"),
    ("scaling.json", "the scaling model's predicted speed-ups at 2-16 threads from recordings on "
     "this machine, against the 16-core reference (`tools/quadrant scaling`)", None),
    ("scaling.md", "the scaling model's report: speed-ups, serial fraction, barriers, per stage",
     "scaling.json"),
    ("history.csv", "per-benchmark medians of every `tools/quadrant bench --record` run "
     "(tools/history.py); date and commit of its last record", None),
    ("history.png", "the history's plot (tools/history.py)", "history.csv"),
    ("icount.json", "instruction counts of the step that `tools/quadrant icount --check` (CI) "
     "compares against; `icount --update` rewrites it", None),
]


# Patterns on the path inside the machine folder, tried first.
PATH_KINDS = [
    ("*/old/*.json", "one round of the old side of an interleaved comparison (Google Benchmark "
     "JSON; the comparison's summary is the .md beside its folder)", None),
    ("*/new/*.json", "one round of the new side of an interleaved comparison (Google Benchmark "
     "JSON; the comparison's summary is the .md beside its folder)", None),
]


def kind_of(rel):
    """(description, source JSON's name) of a file by its path inside results/<machine>/."""
    for pattern, text, source in PATH_KINDS:
        if fnmatch.fnmatch(rel, pattern):
            return text, source
    name = os.path.basename(rel)
    for pattern, text, source in KINDS:
        if fnmatch.fnmatch(name, pattern):
            stem = name[len(pattern.split("*")[0]):-len(pattern.split("*")[-1])] if "*" in pattern else ""
            return text.format(stem=stem), source
    return None, None


# ---- the files ------------------------------------------------------------------------------


def git(root, *args):
    """git's stdout, or None outside a checkout (or without git)."""
    try:
        r = subprocess.run(["git", "-C", root, *args], capture_output=True, text=True)
    except OSError:
        return None
    return r.stdout if r.returncode == 0 else None


def result_files(root):
    """Paths under results/ (relative to it) that the index lists, sorted."""
    results = os.path.join(root, "results")
    files = None
    if git(root, "rev-parse", "--is-inside-work-tree") is not None:
        out = git(root, "ls-files", "-z", "--cached", "--others", "--exclude-standard", "--", "results")
        if out is not None:
            files = {os.path.relpath(os.path.join(root, p), results) for p in out.split("\0") if p}
    if files is None:
        files = set()
        for dirpath, dirnames, filenames in os.walk(results):
            rel = os.path.relpath(dirpath, results)
            dirnames[:] = [d for d in dirnames if ".failed-" not in d and not (rel == "." and d == "baselines")]
            files |= {os.path.normpath(os.path.join(rel, f)) for f in filenames}
    return sorted(f for f in files if f != INDEX and os.path.isfile(os.path.join(results, f)))


# ---- dates and commits ------------------------------------------------------------------------


def utc(text):
    """'2026-11-27 11:32 UTC' for an ISO 8601 time, else the text as it is."""
    try:
        t = datetime.datetime.fromisoformat(str(text).replace("Z", "+00:00"))
    except ValueError:
        return str(text)
    if t.tzinfo is not None:
        t = t.astimezone(datetime.timezone.utc)
    return t.strftime("%Y-%m-%d %H:%M UTC")


class Records:
    """Date and commit per file, read once."""

    def __init__(self, root):
        self.root = root
        self.results = os.path.join(root, "results")
        self.in_git = git(root, "rev-parse", "--is-inside-work-tree") is not None
        self._json = {}

    def json(self, rel):
        if rel not in self._json:
            try:
                with open(os.path.join(self.results, rel), encoding="utf-8") as f:
                    self._json[rel] = json.load(f)
            except (OSError, ValueError):
                self._json[rel] = None
        return self._json[rel]

    def context(self, rel):
        """(date, commit) recorded in a JSON file (its "context", else its top level)."""
        data = self.json(rel)
        if not isinstance(data, dict):
            return None, None
        ctx = data.get("context") if isinstance(data.get("context"), dict) else data
        date, commit = ctx.get("date"), ctx.get("commit")
        return (utc(date) if isinstance(date, str) and date else None,
                commit if isinstance(commit, str) and commit else None)

    def history(self, rel):
        """(date, commit) of history.csv's last record."""
        try:
            with open(os.path.join(self.results, rel), encoding="utf-8") as f:
                rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
        except OSError:
            return None, None
        if len(rows) < 2 or "date" not in rows[0] or "commit" not in rows[0]:
            return None, None
        last = rows[-1]
        i, j = rows[0].index("date"), rows[0].index("commit")
        return (utc(last[i]) if len(last) > i else None), (last[j] if len(last) > j else None)

    def git_date(self, rel):
        if not self.in_git:
            return "not in git"
        path = os.path.join("results", rel)
        out = git(self.root, "log", "-1", "--format=%aI", "--", path)
        if out and out.strip():
            return utc(out.strip()) + " (git)"
        return "not committed yet"

    def of(self, rel, source):
        """(date, commit, source used) of a file."""
        directory, name = os.path.split(rel)
        date = commit = None
        used = None
        if name.endswith(".json"):
            date, commit = self.context(rel)
        elif name == "history.csv":
            date, commit = self.history(rel)
        if not (date or commit) and source:
            src = os.path.join(directory, source)
            if os.path.isfile(os.path.join(self.results, src)):
                date, commit = self.history(src) if source == "history.csv" else self.context(src)
                if date or commit:
                    used = src
        if not date:
            date = self.git_date(rel)
        return date, commit or "", used


# ---- machines ---------------------------------------------------------------------------------


def describe_machine(records, machine, files):
    """One line: CPU, cores, clock, host and compiler from the folder's JSON contexts."""
    facts = {}
    for rel in files:
        if not rel.endswith(".json"):
            continue
        data = records.json(rel)
        ctx = data.get("context") if isinstance(data, dict) and isinstance(data.get("context"), dict) else None
        if not ctx:
            continue
        for key in ("cpu_model", "num_cpus", "mhz_per_cpu", "host_name", "compiler"):
            if key not in facts and ctx.get(key) not in (None, ""):
                facts[key] = (ctx[key], os.path.relpath(rel, machine))
    parts = []
    if "cpu_model" in facts:
        cpu = str(facts["cpu_model"][0])
        if "mhz_per_cpu" in facts:
            cpu += f" ({facts['mhz_per_cpu'][0]} MHz)"
        parts.append(f"CPU {cpu}")
    if "num_cpus" in facts:
        parts.append(f"{facts['num_cpus'][0]} cores")
    if "host_name" in facts:
        parts.append(f"host name `{facts['host_name'][0]}`")
    if "compiler" in facts:
        compiler = str(facts["compiler"][0])
        parts.append(f"compiler {'GCC ' + compiler if re.match(r'^[0-9.]+$', compiler) else compiler}")
    if not parts:
        return "no JSON context in this folder says which machine it is"
    sources = sorted({s for _, s in facts.values()})
    return "; ".join(parts) + " (from the JSON context of " + ", ".join(f"`{s}`" for s in sources) + ")"


# ---- the index --------------------------------------------------------------------------------

HEADER = """# results/: the committed record

Generated by `tools/results_index.py` (`tools/quadrant results-index`); do not edit by hand. The
driver regenerates it after every command that writes into results/, and the test
`results_index` (tests/tools/results_index_test.py) fails when a file under results/ is missing
from it.

What is committed here: per machine (`results/<machine>/`, where `<machine>` is
`$QUADRANT_MACHINE` or the CPU model and core count), the current reference run of each
command: bench.json with speedup.md and the fps_*.png plots, bench_busy.json where there is one,
the hard-case, validation, accuracy, effects, distributed and queries reports, and
comparisons.md, the summaries of interleaved comparisons; at the top, history.csv and
history.png (`bench --record`) and icount.json (CI's `tools/quadrant icount --check`).

What is not committed: the commands' default runs (since issue #29 they go to
`runs/<machine>/<YYYYmmdd-HHMMSS>/`, which git ignores; only `--record` or `--out results/...`
writes here), the raw rounds of interleaved comparisons (tools/compare_commits.sh,
tools/interleave.sh: write them under runs/ and add their summary to the machine's
comparisons.md), the machine's baseline (`results/baselines/`, ignored) and failed runs' outputs
(`*.failed-*`, ignored).

Date and commit: the run's own (its JSON context, or the JSON that the report or plot was drawn
from, named in the table); "(git)" marks a date that is only the file's last commit.
"""


def render(root):
    records = Records(root)
    files = result_files(root)
    top = [f for f in files if os.sep not in f]
    machines = sorted({f.split(os.sep)[0] for f in files if os.sep in f})
    out = [HEADER]

    def table(rels, base):
        rows = ["| file | what it is | date | commit |", "|---|---|---|---|"]
        for rel in rels:
            text, source = kind_of(os.path.relpath(rel, base) if base else rel)
            if text is None:
                text = first_heading(os.path.join(records.results, rel)) or "(not described: add its kind to tools/results_index.py)"
            date, commit, used = records.of(rel, source)
            if used:
                text += f"; date and commit of `{(os.path.relpath(used, base) if base else used).replace(os.sep, '/')}`"
            shown = (os.path.relpath(rel, base) if base else rel).replace(os.sep, "/")
            link = rel.replace(os.sep, "/")
            rows.append(f"| [`{shown}`]({link}) | {text} | {date} | {f'`{commit}`' if commit else ''} |")
        return rows

    if top:
        out += ["## results/ (all machines)", ""] + table(top, "") + [""]
    for machine in machines:
        rels = [f for f in files if f.startswith(machine + os.sep)]
        out += [f"## {machine}/", "",
                f"Machine: {describe_machine(records, machine, rels)}. {len(rels)} files.", ""]
        out += table(rels, machine) + [""]
    return "\n".join(out).rstrip("\n") + "\n"


def first_heading(path):
    """A Markdown or text file's first heading ('# ...'), as a description of an unknown file."""
    if not path.endswith((".md", ".txt")):
        return None
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.startswith("#"):
                    return line.lstrip("#").strip().replace("|", "\\|")
    except (OSError, UnicodeDecodeError):
        pass
    return None


LINK_RE = re.compile(r"^\| \[`[^`]*`\]\(([^)]+)\) \|", re.M)


def listed(text):
    return {m.replace("/", os.sep) for m in LINK_RE.findall(text)}


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", default=ROOT, help="the checkout (default: this script's)")
    ap.add_argument("--check", action="store_true",
                    help="exit 1 if results/README.md misses a file or lists one that is gone")
    args = ap.parse_args(argv)
    root = os.path.abspath(args.root)
    path = os.path.join(root, "results", INDEX)
    text = render(root)
    if args.check:
        try:
            with open(path, encoding="utf-8") as f:
                current = f.read()
        except OSError as e:
            print(f"results_index: {path}: cannot read ({e.strerror}); write it: tools/quadrant results-index",
                  file=sys.stderr)
            return 1
        files = set(result_files(root))
        have = listed(current)
        missing, gone = sorted(files - have), sorted(have - files)
        for f in missing:
            print(f"results_index: results/{f} is not in results/README.md", file=sys.stderr)
        for f in gone:
            print(f"results_index: results/README.md lists results/{f}, which is not there", file=sys.stderr)
        if missing or gone:
            print("results_index: regenerate it: tools/quadrant results-index", file=sys.stderr)
            return 1
        if current != text:
            print("results_index: results/README.md lists every file; its dates or descriptions differ from "
                  "a fresh one (tools/quadrant results-index rewrites it)")
        print(f"results_index: results/README.md lists all {len(files)} files")
        return 0
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    print(f"results_index: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
