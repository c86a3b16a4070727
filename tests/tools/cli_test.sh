#!/usr/bin/env bash
# The command line is right or silent (issue 16; docs/bad_input.md, "Command line"): every bad
# option gives exactly one line on stderr naming the option, nothing on stdout, exit status 2,
# and leaves the output directory's previous results untouched; the programs behind the driver
# refuse bad names before running anything. Checks the driver's refusals (made before any
# build, so they need no binary) and the built programs' own.
# usage: cli_test.sh ROOT QUADRANT_BENCH QUADRANT_HARDCASES QUADRANT_VALIDATE
set -uo pipefail
ROOT="$1" BENCH="$2" HARDCASES="$3" VALIDATE="$4"
DRIVER="$ROOT/tools/quadrant"
WORK="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-cli-test.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

OUT="$WORK/results"
mkdir -p "$OUT"
echo '{"previous run": true}' >"$OUT/bench.json"
echo "previous report" >"$OUT/speedup.md"
touch "$WORK/a_file"
snapshot() { (cd "$OUT" && find . -type f -exec sha256sum {} + | sort); }
BEFORE="$(snapshot)"

# expect_refusal WANT_TEXT CMD...: exit 2, one stderr line containing WANT_TEXT, empty stdout,
# the output directory unchanged.
expect_refusal() {
  local want="$1"
  shift
  local status=0
  "$@" >"$WORK/stdout" 2>"$WORK/stderr" </dev/null || status=$?
  local what="$*"
  what="${what//$WORK/WORK}"
  ((status == 2)) || fail "$what: exit $status, expected 2"
  local lines
  lines="$(wc -l <"$WORK/stderr")"
  ((lines == 1)) || fail "$what: $lines lines on stderr, expected 1: $(head -c 600 "$WORK/stderr")"
  grep -qF -- "$want" "$WORK/stderr" || fail "$what: stderr lacks '$want': $(cat "$WORK/stderr")"
  [[ ! -s "$WORK/stdout" ]] || fail "$what: printed on stdout: $(head -c 300 "$WORK/stdout")"
  grep -qiE "traceback|usage: quadrant_|benchmark_" "$WORK/stderr" && fail "$what: internal text on stderr"
  [[ "$(snapshot)" == "$BEFORE" ]] || fail "$what: the output directory changed"
  echo "ok: $what -> $(cat "$WORK/stderr")"
}

# The driver: refused before anything is built (the rows of docs/bad_input.md).
for args in "--counts abc" "--counts 0" "--counts -5" "--counts 1000,,2000" "--counts ,1000" \
            "--counts 1000," "--threads 0" "--threads 100" "--threads 1,x" "--repetitions 0" \
            "--repetitions abc" "--steps 0" "--warmup -1" "--busy x" "--busy -1" "--busy 65"; do
  read -ra words <<<"$args"
  expect_refusal "${words[0]}" "$DRIVER" bench "${words[@]}" --out "$OUT"
done
expect_refusal "--engines" "$DRIVER" bench --engines , --out "$OUT"
expect_refusal "--engines" "$DRIVER" bench --engines quadrant,, --out "$OUT"
expect_refusal "unknown engine 'nosuchengine'" "$DRIVER" bench --engines nosuchengine --out "$OUT"
expect_refusal "--scenes" "$DRIVER" bench --scenes 'a b' --out "$OUT"
expect_refusal "is not a directory" "$DRIVER" bench --out "$WORK/a_file/sub"
expect_refusal "is not a directory" "$DRIVER" bench --out "$WORK/a_file"
expect_refusal "unknown option '--frob'" "$DRIVER" bench --frob 1 --out "$OUT"
expect_refusal "--busy measures a loaded machine" "$DRIVER" bench --busy 1 --compare --out "$OUT"
expect_refusal "--steps needs a value" "$DRIVER" bench --out "$OUT" --steps=
expect_refusal "--counts needs a value" "$DRIVER" bench --out "$OUT" --counts
expect_refusal "exclude each other" "$DRIVER" bench --baseline --compare --out "$OUT"
# bench --ranks (the distributed runs): its own options only, rank counts in [1, 64].
expect_refusal "--ranks '0'" "$DRIVER" bench --ranks 0 --out "$OUT"
expect_refusal "--ranks '1,,2'" "$DRIVER" bench --ranks 1,,2 --out "$OUT"
expect_refusal "only --steps, --out and --record" "$DRIVER" bench --ranks 1,2 --threads 2 --out "$OUT"
expect_refusal "--steps '0'" "$DRIVER" bench --ranks 1 --steps 0 --out "$OUT"
expect_refusal "unknown command 'benhc'" "$DRIVER" benhc
expect_refusal "unknown engine 'nosuchengine'" "$DRIVER" hardcases --peers nosuchengine --out "$OUT"
expect_refusal "--soak-steps" "$DRIVER" hardcases --soak-steps 0 --out "$OUT"
expect_refusal "is not a directory" "$DRIVER" validate --out "$WORK/a_file/x"
expect_refusal "is not a directory" "$DRIVER" figure13 --out "$WORK/a_file/x"
expect_refusal "unknown argument '--nope'" "$DRIVER" accuracy --nope
expect_refusal "unknown argument '--nope'" "$DRIVER" effects --nope
expect_refusal "unknown argument '--nope'" "$DRIVER" results-index --nope

# The programs themselves: one line, exit 2, nothing run.
expect_refusal "--counts" "$BENCH" --counts abc
expect_refusal "--counts" "$BENCH" --counts 1000,,2000
expect_refusal "--threads" "$BENCH" --threads 0
expect_refusal "--engines" "$BENCH" --engines ,
expect_refusal "unknown engine 'nosuchengine'" "$BENCH" --engines nosuchengine --counts 10 --threads 1
expect_refusal "unknown quadrant variant 'bogus'" "$BENCH" --engines quadrant:bogus --counts 10 --threads 1
expect_refusal "unknown scene 'nosuch'" "$BENCH" --scenes nosuch --counts 10 --threads 1
expect_refusal "nothing to run" "$BENCH" --scenes circle_stress --engines box2d --threads 2 --counts 10
expect_refusal "unknown engine 'nosuchengine'" "$HARDCASES" --out "$OUT" --peers nosuchengine
expect_refusal "unknown case 'nosuch'" "$HARDCASES" --out "$OUT" --cases nosuch
expect_refusal "unknown case 'nosuch'" "$VALIDATE" --out "$OUT" --cases nosuch

# help lists every engine and scene the suite knows.
help="$("$DRIVER" help)"
while read -r kind name; do
  grep -qE "^  $name( |$)" <<<"$help" || fail "help does not list $kind $name"
done < <("$BENCH" --list | sed 's/: / /')
grep -q "soft_step" <<<"$help" || fail "help does not list the quadrant variants"

((failures == 0)) || { echo "$failures failure(s)"; exit 1; }
echo "all command-line refusals are one line, exit 2, outputs untouched"
