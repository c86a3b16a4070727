#!/usr/bin/python3
"""Instruction counts of the engine's step, checked against committed counts.

Usage (driven by tools/quadrant icount, which builds the release preset's quadrant_icount first):

    /usr/bin/python3 tools/icount.py [--check | --update] [--tolerance PCT]
                                     [--binary PATH] [--json PATH] [--valgrind PATH]

Each scene of SCENES is stepped by quadrant_icount under valgrind's callgrind, counting only the
steps (the program switches collection on around its stepping loop; building and loading the
scene are not counted). Callgrind counts executed instructions exactly, so for the same binary
and input the count repeats to the last instruction: unlike timings, it can catch a 3 % change
in the work the engine does on a noisy shared machine.

--check (default): measures, compares with the committed counts (results/icount.json) and
    exits 1 if any scene moved by more than the tolerance (default: the file's tolerance_pct,
    2 %) in EITHER direction, or if the scene sets differ. A drop is a failure too: the committed
    counts are the reference for the next change, so a real improvement must be committed (with
    --update) or later regressions up to the size of the improvement would go unnoticed.
    Exits 2 (refuses) when the binary was built by another compiler than the counts were:
    different code generation gives different counts, and the comparison would mean nothing.
--update: measures and rewrites the JSON. Commit it with a message that says why the counts
    changed.

Exit status: 0 all within tolerance (or updated), 1 out of tolerance, 2 cannot measure or compare
(valgrind or the binary missing, malformed JSON, different compiler).
"""

import argparse
import datetime
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_BINARY = os.path.join(ROOT, "build", "release", "benchmarks", "quadrant_icount")
DEFAULT_JSON = os.path.join(ROOT, "results", "icount.json")
DEFAULT_TOLERANCE_PCT = 2.0

# (scene, count, steps): the stress scenes at N = 1000 and a base-20 pyramid (count = base), 60
# steps each: a few seconds under callgrind in all, yet every stage of the step is exercised
# (many free bodies; many resting contacts with warm starting and friction).
SCENES = [("circle_stress", 1000, 60), ("polygon_stress", 1000, 60), ("pyramid", 20, 60)]

# CPU features that change which variants of memcpy/memset and libm functions glibc picks (its
# ifunc resolvers read CPUID, which valgrind emulates from the host's): a machine without them
# may count somewhat differently with the same binary.
CPU_FEATURES = ("sse4_2", "avx", "avx2", "fma", "avx512f")


class IcountError(Exception):
    """Cannot measure or compare: exit status 2."""


def cpu_model_and_features():
    model, flags = "unknown", set()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            for line in f:
                key, _, value = line.partition(":")
                key = key.strip()
                if key == "model name" and model == "unknown":
                    model = value.strip()
                elif key == "flags" and not flags:
                    flags = set(value.split())
    except OSError:
        pass
    return model, [f for f in CPU_FEATURES if f in flags]


def commit_id():
    """QUADRANT_COMMIT (set by tools/quadrant), else the short HEAD, read-only."""
    if os.environ.get("QUADRANT_COMMIT"):
        return os.environ["QUADRANT_COMMIT"]
    try:
        return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], check=True,
                              capture_output=True, text=True).stdout.strip() or "unknown"
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def build_info(binary):
    """compiler, build_type, cxx_flags and extra_work of the binary (its --info output)."""
    if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
        raise IcountError(f"{binary}: no such executable (build it: tools/quadrant build, target "
                          "quadrant_icount, or pass --binary)")
    proc = subprocess.run([binary, "--info"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise IcountError(f"{binary} --info failed (exit {proc.returncode}): {proc.stderr.strip()}")
    info = dict(line.split("=", 1) for line in proc.stdout.splitlines() if "=" in line)
    for key in ("compiler", "build_type", "cxx_flags", "extra_work"):
        if key not in info:
            raise IcountError(f"{binary} --info does not say {key}: is it quadrant_icount?")
    return info


def valgrind_version(valgrind):
    try:
        return subprocess.run([valgrind, "--version"], capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError) as e:
        raise IcountError(f"cannot run {valgrind} --version: {e} (install the Debian package "
                          "valgrind: tools/quadrant setup)")


def read_callgrind_total(path):
    """The instruction count (Ir) of a callgrind output file: its totals: line (or summary:)."""
    totals, summary = None, None
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("totals:"):
                totals = int(line.split()[1])
            elif line.startswith("summary:"):
                summary = int(line.split()[1])
    value = totals if totals is not None else summary
    if value is None:
        raise IcountError(f"{path}: no totals: or summary: line (not a callgrind output?)")
    return value


def measure(binary, valgrind, scene, count, steps, workdir):
    """Runs one scene under callgrind; returns (key, instructions, state hash)."""
    out = os.path.join(workdir, f"callgrind.{scene}.out")
    cmd = [valgrind, "--tool=callgrind", "--instr-atstart=no", "--collect-atstart=no",
           f"--callgrind-out-file={out}", binary, "--scene", scene, "--count", str(count),
           "--steps", str(steps)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-15:])
        raise IcountError(f"{' '.join(cmd)} failed (exit {proc.returncode}):\n{tail}")
    m = re.search(r"^key=(\S+) .*hash=([0-9a-f]+)", proc.stdout, re.M)
    if not m:
        raise IcountError(f"{binary} printed no key=... line for {scene}: {proc.stdout.strip()!r}")
    total = read_callgrind_total(out)
    if total == 0:
        raise IcountError(f"{scene}: callgrind counted 0 instructions: the client requests did not "
                          "reach callgrind (built without valgrind/callgrind.h?)")
    return m.group(1), total, m.group(2)


def load_committed(path):
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except FileNotFoundError:
        raise IcountError(f"{path}: no committed instruction counts; create them with "
                          "tools/quadrant icount --update")
    except (OSError, json.JSONDecodeError) as e:
        raise IcountError(f"{path}: cannot read: {e}")
    if not isinstance(data, dict) or not isinstance(data.get("scenes"), dict) or not all(
            isinstance(v, int) for v in data["scenes"].values()):
        raise IcountError(f'{path}: malformed: expected {{"scenes": {{"<key>": <count>, ...}}, ...}}')
    return data


def main(argv=None):
    parser = argparse.ArgumentParser(prog="icount.py", description=__doc__.split("\n")[0],
                                     epilog="See the module docstring for details.")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true", help="compare with the committed counts (default)")
    mode.add_argument("--update", action="store_true", help="rewrite the committed counts")
    parser.add_argument("--tolerance", type=float, default=None, metavar="PCT",
                        help="allowed change in %% (default: the JSON's tolerance_pct, else 2)")
    parser.add_argument("--binary", default=DEFAULT_BINARY, help="quadrant_icount to measure")
    parser.add_argument("--json", default=DEFAULT_JSON, help="committed counts (results/icount.json)")
    parser.add_argument("--valgrind", default="valgrind", help="valgrind executable")
    args = parser.parse_args(argv)
    if args.tolerance is not None and not 0 <= args.tolerance < 100:
        parser.error("--tolerance must be in [0, 100)")
    try:
        return run(args)
    except IcountError as e:
        print(f"icount: error: {e}", file=sys.stderr)
        return 2


def run(args):
    valgrind = shutil.which(args.valgrind) or (args.valgrind if os.path.isfile(args.valgrind) else None)
    if not valgrind:
        raise IcountError(f"{args.valgrind} not found (install the Debian package valgrind: "
                          "tools/quadrant setup)")
    vg_version = valgrind_version(valgrind)
    info = build_info(args.binary)
    model, features = cpu_model_and_features()

    committed = None
    if not args.update:
        committed = load_committed(args.json)
        if committed.get("compiler") != info["compiler"]:
            raise IcountError(
                f"{args.binary} was built by {info['compiler']!r}, the counts in {args.json} by "
                f"{committed.get('compiler')!r}: instruction counts of different compilers are not "
                "comparable. Build with the recorded compiler, or re-measure with --update (and "
                "say so in the commit message).")
        for key, have in (("build_type", info["build_type"]), ("cxx_flags", info["cxx_flags"]),
                          ("valgrind", vg_version), ("cpu_features", features)):
            if key in committed and committed[key] != have:
                print(f"icount: warning: {key} differs: committed {committed[key]!r}, now {have!r}; "
                      "counts may differ for that reason", file=sys.stderr)
    elif info["extra_work"] != "0":
        raise IcountError(f"{args.binary} was built with QUADRANT_ICOUNT_INJECT_EXTRA_WORK: "
                          "refusing to record its counts")
    if info["extra_work"] != "0":
        print("icount: note: this binary was built with QUADRANT_ICOUNT_INJECT_EXTRA_WORK "
              "(deliberate extra work per step)", file=sys.stderr)

    measured, hashes = {}, {}
    with tempfile.TemporaryDirectory(prefix="quadrant-icount.") as workdir:
        for scene, count, steps in SCENES:
            print(f"icount: {scene} (count {count}, {steps} steps) under callgrind ...",
                  file=sys.stderr, flush=True)
            key, total, state_hash = measure(args.binary, valgrind, scene, count, steps, workdir)
            measured[key], hashes[key] = total, state_hash

    if args.update:
        tolerance = args.tolerance
        if tolerance is None:
            try:
                tolerance = load_committed(args.json).get("tolerance_pct", DEFAULT_TOLERANCE_PCT)
            except IcountError:
                tolerance = DEFAULT_TOLERANCE_PCT
        data = {
            "tolerance_pct": tolerance,
            "machine_note": (
                f"Instructions (callgrind Ir) executed by quadrant_icount's stepping loop only, "
                f"measured with {vg_version} on {model}. They depend on the compiler and its flags "
                "(recorded here; --check refuses another compiler), not on the machine's speed or "
                "load; glibc picks CPU-specific memcpy/libm variants from the (emulated) CPUID, so "
                "a CPU without the features listed in cpu_features may count a little differently; "
                "and soft_step's row and integration kernels and the box-box narrow phase run in AVX's "
                "encoding where the CPU has avx (the same results, fewer instructions): without it "
                "the pyramid counts about 17 % more, the stress scenes about 4 % more."),
            "compiler": info["compiler"],
            "build_type": info["build_type"],
            "cxx_flags": info["cxx_flags"],
            "valgrind": vg_version,
            "cpu_features": features,
            "commit": commit_id(),
            "date": datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0)
                    .isoformat().replace("+00:00", "Z"),
            "scenes": measured,
            "state_hashes": hashes,
        }
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(data, f, indent=2)
            f.write("\n")
        print("| scene | instructions | state hash |\n|---|---:|---|")
        for key in measured:
            print(f"| {key} | {measured[key]:,} | {hashes[key]} |")
        print(f"\nicount: wrote {args.json}. Commit it with a message that says why the counts "
              "changed.")
        return 0

    tolerance = args.tolerance if args.tolerance is not None else float(
        committed.get("tolerance_pct", DEFAULT_TOLERANCE_PCT))
    reference = committed["scenes"]
    old_hashes = committed.get("state_hashes", {})
    failures = []
    print(f"Instruction counts (callgrind, stepping only), tolerance +-{tolerance:g} %, committed "
          f"at {committed.get('commit', '?')}:\n")
    print("| scene | instructions | committed | change | verdict |")
    print("|---|---:|---:|---:|---|")
    for key, total in measured.items():
        if key not in reference:
            print(f"| {key} | {total:,} | - | - | NOT COMMITTED |")
            failures.append(f"{key}: no committed count (a new or renamed scene: run --update)")
            continue
        old = reference[key]
        change = (total - old) / old * 100 if old else float("inf")
        if change > tolerance:
            verdict = "MORE WORK"
            failures.append(f"{key}: {change:+.2f} % instructions")
        elif change < -tolerance:
            verdict = "LESS WORK (commit with --update)"
            failures.append(f"{key}: {change:+.2f} % instructions (a drop: commit it with --update)")
        else:
            verdict = "ok"
        print(f"| {key} | {total:,} | {old:,} | {change:+.2f} % | {verdict} |")
    for key in sorted(set(reference) - set(measured)):
        print(f"| {key} | - | {reference[key]:,} | - | NOT MEASURED |")
        failures.append(f"{key}: committed but no longer measured (renamed or removed: run --update)")
    changed_hashes = [k for k in measured if k in old_hashes and old_hashes[k] != hashes[k]]
    if changed_hashes:
        print(f"\nState hashes differ from the committed ones for {', '.join(changed_hashes)}: "
              "the simulation's results changed, not only its cost.")
    print()
    if failures:
        print("icount: FAILED:")
        for f in failures:
            print(f"  - {f}")
        print(f"A change beyond +-{tolerance:g} % in either direction fails: if it is intended "
              "(more work for a reason, or an optimisation), commit the new counts with "
              "tools/quadrant icount --update and say why in the commit message; a large drop "
              "must be committed too, or later regressions hide behind it.")
        return 1
    print(f"icount: all {len(measured)} scenes within +-{tolerance:g} %.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
