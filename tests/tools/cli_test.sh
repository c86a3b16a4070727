#!/usr/bin/env bash
# The command line is right or silent (issue 16; docs/bad_input.md, "Command line"): every bad
# option gives exactly one line on stderr naming the option, nothing on stdout, exit status 2,
# and leaves the output directory's previous results untouched; the programs behind the driver
# refuse bad names before running anything. Checks the driver's refusals (made before any
# build, so they need no binary) and the built programs' own (every program in QUADRANT_BENCH's
# directory, in program_parsers).
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
            "--repetitions abc" "--steps 0" "--warmup -1" "--busy x" "--busy -1" "--busy 65" \
            "--frame-rate -1" "--frame-rate x" "--frame-rate 10001"; do
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
expect_refusal "--frame-rate times a frame loop" "$DRIVER" bench --frame-rate 60 --compare --out "$OUT"
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

# ---- The benchmark programs' own parser (benchmarks/cli_args.h; issue #28 item 5) ------------
# Every program beside quadrant_bench in the build directory (those the build lacks, without MPI,
# valgrind or Box2D, are skipped): --help exits 0 with its usage and each option on stdout and
# nothing on stderr; a bad value is the one line "<program>: --option: <what it accepts> (got
# '<value>')"; an unknown option or argument is one line naming it. The programs on Google
# Benchmark leave its --benchmark_* flags to it, and a count a scene rounds is named as built.
program_parsers() {
  local dir
  dir="$(dirname "$BENCH")"
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # quadrant_distributed alone, as root

  # expect_help PROGRAM OPTION...: exit 0, "usage: <program>" and every OPTION on stdout, no stderr.
  expect_help() {
    local program="$1" status=0 option
    shift
    [[ -x "$dir/$program" ]] || { echo "skip: $program not built"; return; }
    "$dir/$program" --help >"$WORK/stdout" 2>"$WORK/stderr" </dev/null || status=$?
    ((status == 0)) || fail "$program --help: exit $status, expected 0"
    grep -q "^usage: $program " "$WORK/stdout" || fail "$program --help: no usage line: $(head -c 300 "$WORK/stdout")"
    for option in "$@"; do
      grep -qF -- "  $option" "$WORK/stdout" || fail "$program --help does not list $option"
    done
    [[ ! -s "$WORK/stderr" ]] || fail "$program --help: printed on stderr: $(head -c 300 "$WORK/stderr")"
    echo "ok: $program --help"
  }
  # expect_value_refusal PROGRAM OPTION VALUE WANT ARGS...: ARGS refused in the one-line form for
  # OPTION and VALUE, with WANT in the line.
  expect_value_refusal() {
    local program="$1" option="$2" value="$3" want="$4"
    shift 4
    [[ -x "$dir/$program" ]] || { echo "skip: $program not built"; return; }
    expect_refusal "$want" "$dir/$program" "$@"
    local line
    line="$(cat "$WORK/stderr")"
    [[ "$line" == "$program: $option: "*" (got '$value')" ]] ||
      fail "$program ${*//$WORK/WORK}: not '$program: $option: ... (got '$value')': $line"
  }
  expect_unknown() {
    local program="$1" want="$2"
    shift 2
    [[ -x "$dir/$program" ]] || { echo "skip: $program not built"; return; }
    expect_refusal "$want" "$dir/$program" "$@"
  }

  expect_help quadrant_bench --scenes --engines --counts --threads --steps --warmup --seed --frame-rate --list
  grep -q -- "--benchmark_filter" "$WORK/stdout" || fail "quadrant_bench --help does not go on to Google Benchmark's flags"
  expect_help quadrant_accuracy --out --json --quick --settings --scenes --hard-cases --steps --repetitions --count
  expect_help quadrant_effects --out --quick --count --steps --warmup --repetitions
  expect_help quadrant_hardcases --out --peers --cases --soak-steps
  expect_help quadrant_validate --out --cases --random --seed --runs
  expect_help quadrant_figure13 OUT.csv bodies steps
  expect_help quadrant_icount --scene --count --steps --seed --engine --info
  expect_help quadrant_distributed --scene --count --per-rank --steps --warmup --tiles --iterations --owners
  expect_help quadrant_queries
  expect_help quadrant_task_overhead

  # One kind of value each: an integer with its range, a list of integers, names from a set,
  # an open set checked by the engine, a flag, a positional argument, a missing value.
  expect_value_refusal quadrant_bench --counts 0 "integers in [1, 10000000]" --counts=0
  expect_value_refusal quadrant_bench --threads 1,x "'x' is not an integer" --threads 1,x
  expect_value_refusal quadrant_bench --frame-rate -1 "an integer in [0, 10000]" --frame-rate -1
  expect_value_refusal quadrant_accuracy --steps 0 "an integer in [1, 1000000]" --steps 0
  expect_value_refusal quadrant_accuracy --settings quadrant:thesis,quadrant:nope "unknown setting 'quadrant:nope'" \
    --settings quadrant:thesis,quadrant:nope
  expect_value_refusal quadrant_effects --warmup -1 "an integer in [0, 1000000]" --warmup -1
  expect_value_refusal quadrant_effects --quick 1 "no value" --quick=1
  expect_value_refusal quadrant_hardcases --cases "a,,b" "an empty item" --out "$OUT" --cases a,,b
  expect_value_refusal quadrant_hardcases --peers nosuchengine "unknown engine 'nosuchengine'" \
    --out "$OUT" --peers nosuchengine
  expect_value_refusal quadrant_validate --runs box2d "is not quadrant:<variant>" --out "$OUT" --random 1 --runs box2d
  expect_value_refusal quadrant_validate --seed x "an integer in [0, 2147483647]" --out "$OUT" --seed x
  expect_value_refusal quadrant_figure13 bodies abc "an integer in [1, 10000000]" "$OUT/f.csv" abc
  expect_value_refusal quadrant_icount --scene nosuch "unknown scene 'nosuch'" --scene nosuch --count 1 --steps 1
  expect_value_refusal quadrant_icount --engine quadrant:bogus "unknown quadrant variant 'bogus'" --info --engine quadrant:bogus
  expect_value_refusal quadrant_distributed --scene tumbler "one of circle_stress, pyramid" --scene tumbler
  expect_unknown quadrant_figure13 "OUT.csv: the CSV file to write (got nothing)"
  expect_unknown quadrant_figure13 "unexpected argument '4'" "$OUT/f.csv" 1 2 4
  expect_unknown quadrant_icount "--count: an integer in [1, 1000000] (got nothing)" --scene pyramid --steps 1
  expect_unknown quadrant_effects "--steps: an integer in [1, 1000000] (got nothing)" --steps
  expect_unknown quadrant_accuracy "unknown option '--nope'" --nope 1
  expect_unknown quadrant_validate "unknown option '--nope'" --nope
  expect_unknown quadrant_distributed "unknown option '--nope'" --nope
  expect_unknown quadrant_bench "unknown option '--frob'" --frob
  # (not expect_refusal: the flag's own name has the "benchmark_" that it takes for internal text)
  local status=0
  "$BENCH" --benchmark_nosuch=1 >"$WORK/stdout" 2>"$WORK/stderr" || status=$?
  [[ $status == 2 && ! -s "$WORK/stdout" && "$(cat "$WORK/stderr")" == "quadrant_bench: --benchmark_nosuch: "*" (got '--benchmark_nosuch=1')" ]] ||
    fail "quadrant_bench --benchmark_nosuch=1: exit $status, stderr $(cat "$WORK/stderr")"
  expect_unknown quadrant_queries "unknown option '--frob'" --frob
  expect_unknown quadrant_task_overhead "unexpected argument 'x'" x

  # Google Benchmark's flags pass through; pyramid builds 3 boxes for --counts 5 and 6 for 6:
  # the benchmarks are n:3 and n:6 (issue #29 item 7), and the rounding is said in one line.
  status=0
  "$BENCH" --scenes pyramid --engines quadrant --counts 5,6,4 --threads 1 --benchmark_list_tests=true \
    >"$WORK/stdout" 2>"$WORK/stderr" || status=$?
  ((status == 0)) || fail "quadrant_bench --benchmark_list_tests=true: exit $status: $(cat "$WORK/stderr")"
  [[ "$(cat "$WORK/stdout")" == $'pyramid/quadrant/n:3/threads:1/iterations:1/real_time\npyramid/quadrant/n:6/threads:1/iterations:1/real_time' ]] ||
    fail "quadrant_bench --counts 5,6,4 on pyramid: listed $(tr '\n' ' ' <"$WORK/stdout"), expected n:3 and n:6"
  grep -qF "pyramid:5->3, pyramid:4->3" "$WORK/stderr" || fail "quadrant_bench does not say pyramid:5->3: $(cat "$WORK/stderr")"
  echo "ok: quadrant_bench --benchmark_list_tests=true: n:3, n:6 for pyramid --counts 5,6,4"
}
program_parsers
[[ "$(snapshot)" == "$BEFORE" ]] || fail "the programs' refusals changed the output directory"
# ---- end of the benchmark programs' parser -----------------------------------------------------

((failures == 0)) || { echo "$failures failure(s)"; exit 1; }
echo "all command-line refusals are one line, exit 2, outputs untouched"
