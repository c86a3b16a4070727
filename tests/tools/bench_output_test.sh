#!/usr/bin/env bash
# Where tools/quadrant writes (issue #29): a default run goes into a new runs/<machine>/<stamp>/
# and leaves results/ (the committed reference) as it was; only --out results/... or --record
# write into results/, and then results/README.md is regenerated and lists the new files. Runs
# the driver of a temporary copy of the checkout (tools/, results/ and .gitignore, committed in a
# fresh git repository; a temporary HOME) on the built programs (QUADRANT_BIN_DIR: nothing is
# set up or built), each on a tiny configuration (about 20 s in all).
#
# usage: bench_output_test.sh ROOT BIN_DIR     (BIN_DIR: the build's benchmarks/ directory)
set -uo pipefail
if (($# != 2)); then
  echo "usage: $0 ROOT BIN_DIR" >&2
  exit 2
fi
ROOT="$1" BINDIR="$(cd "$2" && pwd)"
PYTHON=/usr/bin/python3
WORK="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-output-test.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
# ok TEXT: prints TEXT if no check failed since the last ok.
reported=0
ok() { ((failures > reported)) || echo "ok: $*"; reported=$failures; }

CLONE="$WORK/clone"
mkdir -p "$CLONE" "$WORK/home"
cp -R "$ROOT/tools" "$ROOT/results" "$ROOT/.gitignore" "$CLONE/"
rm -rf "$CLONE/results/baselines"
find "$CLONE/results" -depth -name '*.failed-*' -exec rm -rf {} +
git_in_clone() { git -C "$CLONE" -c user.name=test -c user.email=test@example.invalid "$@"; }
if command -v git >/dev/null; then
  git_in_clone init -q && git_in_clone add -A && git_in_clone commit -q -m "the copy" ||
    { echo "FAIL: could not make the copy a git repository"; exit 1; }
fi

snapshot() { (cd "$CLONE/results" && find . -type f -exec sha256sum {} + | sort); }
BEFORE="$(snapshot)"

# quadrant ARGS...: the copy's driver with a temporary HOME and the built programs; stdout and
# stderr in $WORK/out and $WORK/err; sets $status.
quadrant() {
  status=0
  HOME="$WORK/home" QUADRANT_BIN_DIR="$BINDIR" "$CLONE/tools/quadrant" "$@" >"$WORK/out" 2>"$WORK/err" </dev/null || status=$?
}
TINY=(--scenes circle_stress --engines quadrant --counts 50 --threads 1 --repetitions 1 --steps 3 --warmup 1)

# 1. The default bench (the machine's own name, as a new user's first run): runs/, not results/.
unset QUADRANT_MACHINE
quadrant bench "${TINY[@]}"
((status == 0)) || fail "bench: exit $status: $(tail -n 5 "$WORK/err")"
[[ "$(snapshot)" == "$BEFORE" ]] || fail "bench without --out or --record changed results/: $(diff <(echo "$BEFORE") <(snapshot) | head -n 5)"
run=""
mapfile -t runs < <(cd "$CLONE" && find runs -mindepth 2 -maxdepth 2 -type d 2>/dev/null)
if ((${#runs[@]} != 1)); then
  fail "bench: expected one directory runs/<machine>/<stamp>/, found ${#runs[@]}: ${runs[*]-}"
else
  run="${runs[0]}"
  [[ "$run" =~ ^runs/[a-z0-9-]+/[0-9]{8}-[0-9]{6}$ ]] || fail "bench: run directory '$run' is not runs/<machine>/<YYYYmmdd-HHMMSS>"
  for f in bench.json speedup.md fps_circle_stress.png; do
    [[ -s "$CLONE/$run/$f" ]] || fail "bench: $run/$f missing or empty"
  done
  last="$(tail -n 1 "$WORK/err")"
  [[ "$last" == *"outputs in $run/"*"not committed"* ]] || fail "bench: the last line does not say where the outputs went: $last"
fi
if command -v git >/dev/null; then
  [[ -z "$(git_in_clone status --porcelain)" ]] || fail "git status is not clean after the default bench: $(git_in_clone status --porcelain | head -n 5)"
fi
ok "default bench -> ${run:-?}; results/ unchanged, git status clean"

# 2. A default report command (validate, one case): runs/ too.
quadrant validate --cases head_on_1to1_e0
((status == 0)) || fail "validate: exit $status: $(tail -n 5 "$WORK/err")"
[[ "$(snapshot)" == "$BEFORE" ]] || fail "validate without --out or --record changed results/"
[[ -n "$(cd "$CLONE" && find runs -name validation.json 2>/dev/null)" ]] || fail "validate: no runs/<machine>/<stamp>/validation.json"
ok "default validate -> runs/; results/ unchanged"

# 3. An explicit --out results/<machine>: written there, results/README.md regenerated.
export QUADRANT_MACHINE=output-test
quadrant bench "${TINY[@]}" --out "$CLONE/results/output-test"
((status == 0)) || fail "bench --out results/output-test: exit $status: $(tail -n 5 "$WORK/err")"
[[ -s "$CLONE/results/output-test/bench.json" ]] || fail "bench --out results/output-test wrote no bench.json"
grep -qF '](output-test/bench.json)' "$CLONE/results/README.md" || fail "results/README.md does not list output-test/bench.json"
[[ "$(tail -n 1 "$WORK/err")" == *"outputs in results/output-test/, the committed reference"* ]] ||
  fail "bench --out results/...: the last line does not say so: $(tail -n 1 "$WORK/err")"
ok "bench --out results/output-test -> results/output-test/, index regenerated"

# 4. --record on a report command: results/<machine>/.
quadrant validate --record --cases head_on_1to1_e0
((status == 0)) || fail "validate --record: exit $status: $(tail -n 5 "$WORK/err")"
[[ -s "$CLONE/results/output-test/validation.json" ]] || fail "validate --record wrote no results/output-test/validation.json"
grep -qF '](output-test/validation.json)' "$CLONE/results/README.md" || fail "results/README.md does not list output-test/validation.json"
"$PYTHON" "$CLONE/tools/results_index.py" --root "$CLONE" --check >/dev/null 2>&1 || fail "results_index.py --check fails after --record"
ok "validate --record -> results/output-test/, index regenerated"

((failures == 0)) || { echo "$failures failure(s)"; exit 1; }
echo "default runs go to runs/, results/ only with --out results/... or --record"
