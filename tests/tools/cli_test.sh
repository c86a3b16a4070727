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
expect_refusal "only --steps, --repetitions, --out and --record" "$DRIVER" bench --ranks 1,2 --threads 2 --out "$OUT"
expect_refusal "--repetitions '0'" "$DRIVER" bench --ranks 1 --repetitions 0 --out "$OUT"
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
# An output path under a file is refused before the run, not after it (the programs themselves).
expect_refusal "is not a directory" "$VALIDATE" --out "$WORK/a_file/x" --random 2 --seeds 1
expect_refusal "is not a directory" "$HARDCASES" --out "$WORK/a_file/x" --cases confined

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
  expect_help quadrant_validate --out --cases --random --seed --seeds --runs
  expect_help quadrant_figure13 OUT.csv bodies steps
  expect_help quadrant_icount --scene --count --steps --seed --engine --info
  expect_help quadrant_distributed --scene --count --per-rank --steps --warmup --tiles --solver --iterations --threads --world --owners --independent
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
  expect_value_refusal quadrant_validate --seeds 0 "an integer in [1, 1000]" --out "$OUT" --random 1 --seeds 0
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
  expect_unknown quadrant_distributed "--independent needs --per-rank" --independent
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

# ---- The first hour (issue #29 items 7 and 8) ------------------------------------------------------
# Bad invocations that used to cost a build or print a page: each is one line naming the option
# and what it accepts, exit 2, and nothing built (a cmake that records being called is first on
# PATH); each command's --help is its own; the driver's static lists agree with the built
# programs; Chipmunk's debug-build noise is one summary line.
first_hour() {
  local fake="$WORK/fake-cmake" marker="$WORK/cmake-called"
  mkdir -p "$fake"
  printf '#!/bin/sh\necho "$*" >>"%s"\nexit 99\n' "$marker" >"$fake/cmake"
  chmod +x "$fake/cmake"
  local path="$fake:$PATH"
  nobuild() { PATH="$path" "$@"; }

  expect_refusal "--seed '-1' is not an integer in [0, 2147483647]" nobuild "$DRIVER" validate --seed -1
  expect_refusal "--seeds '0' is not an integer in [1, 1000]" nobuild "$DRIVER" validate --random 5 --seeds 0
  expect_refusal "build: unknown preset 'nope' (accepted: release, debug" nobuild "$DRIVER" build nope
  expect_refusal "test: unknown preset 'nope' (accepted: release, debug" nobuild "$DRIVER" test --preset nope
  expect_refusal "unknown quadrant variant 'bogus' in 'quadrant:bogus' (accepted: tokens joined by '+': thesis" \
    nobuild "$DRIVER" bench --engines quadrant:bogus
  expect_refusal "unknown quadrant variant 'bogus'" nobuild "$DRIVER" hardcases --peers quadrant:soft_step+bogus
  expect_refusal "unknown quadrant variant 'bogus'" nobuild "$DRIVER" validate --random 5 --runs quadrant:bogus
  expect_refusal "--runs: 'box2d' is not quadrant:<variant>" nobuild "$DRIVER" validate --random 5 --runs box2d
  expect_refusal "--cases: unknown case 'nosuch' (accepted: vertical_stack," nobuild "$DRIVER" hardcases --cases nosuch
  expect_refusal "--cases: unknown case 'nosuch' (accepted: head_on_1to1_e0," nobuild "$DRIVER" validate --cases nosuch
  expect_refusal "--scenes: unknown scene 'nosuch' (accepted: circle_stress," nobuild "$DRIVER" bench --scenes nosuch
  expect_refusal "nothing to run" nobuild "$DRIVER" bench --engines box2d --threads 2
  expect_refusal "nothing to run" nobuild "$DRIVER" bench --engines box2d,bullet,chipmunk --threads 3,4
  expect_refusal "bullet runs no tumbler" nobuild "$DRIVER" bench --engines bullet --scenes tumbler
  expect_refusal "unknown option '--peers'" nobuild "$DRIVER" validate --peers box2d
  [[ ! -e "$marker" ]] || fail "a refusal ran cmake: $(cat "$marker")"

  # --help: the command's own options, on stdout, exit 0, not the whole 116-line text.
  local cmd want status lines
  for cmd in hardcases validate compare build test figure13 icount accuracy effects results-index bench; do
    status=0
    nobuild "$DRIVER" "$cmd" --help >"$WORK/stdout" 2>"$WORK/stderr" || status=$?
    lines="$(wc -l <"$WORK/stdout")"
    ((status == 0)) || fail "$cmd --help: exit $status"
    [[ ! -s "$WORK/stderr" ]] || fail "$cmd --help: printed on stderr: $(head -c 300 "$WORK/stderr")"
    grep -q "^usage: tools/quadrant $cmd " "$WORK/stdout" || fail "$cmd --help: no usage line"
    grep -qE "^  $cmd( |$)" "$WORK/stdout" || fail "$cmd --help: not its own section"
    for other in hardcases validate compare icount figure13; do
      [[ "$other" == "$cmd" ]] || ! grep -qE "^  $other " "$WORK/stdout" || fail "$cmd --help shows $other's section"
    done
    case "$cmd" in
      hardcases) want="--soak-steps --peers --cases"; ((lines < 60)) || fail "hardcases --help: $lines lines" ;;
      validate) want="--random --seed --seeds --runs --cases"; ((lines < 30)) || fail "validate --help: $lines lines" ;;
      compare) want="--min-repetitions --allow-load --all --threshold"; ((lines < 40)) || fail "compare --help: $lines lines" ;;
      bench) want="--engines --repetitions --busy"; ((lines < 150)) || fail "bench --help: $lines lines" ;;
      *) want=""; ((lines < 20)) || fail "$cmd --help: $lines lines" ;;
    esac
    for option in $want; do grep -qF -- "$option" "$WORK/stdout" || fail "$cmd --help does not list $option"; done
    echo "ok: $cmd --help ($lines lines)"
  done
  grep -q "quadrant:quadrants" <(nobuild "$DRIVER" bench --help) ||
    fail "bench --help does not say that the default engines include quadrant:quadrants"
  [[ ! -e "$marker" ]] || fail "a --help ran cmake: $(cat "$marker")"

  # The static lists the driver checks before a build, against the built programs.
  # (read into DRIVER_<name>: HARDCASES is this script's path of quadrant_hardcases)
  local DRIVER_SCENES DRIVER_VARIANT_TOKENS DRIVER_HARDCASES DRIVER_VALIDATION_CASES
  eval "$(sed -n '/^SCENES=(/,/)$/p; /^VARIANT_TOKENS=(/,/)$/p; /^HARDCASES=(/,/)$/p; /^VALIDATION_CASES=(/,/)$/p' "$DRIVER" |
          sed 's/^\([A-Z_]*\)=(/DRIVER_\1=(/')"
  eval "$(grep -E '^declare -A (ENGINE_MAX_THREADS|ENGINE_REFUSES_SCENE)=' "$DRIVER" | sed 's/^declare -A /local -A DRIVER_/')"
  local known
  known="$("$BENCH" --list | sed -n 's/^scene: //p' | paste -sd' ')"
  [[ "$known" == "${DRIVER_SCENES[*]}" ]] || fail "tools/quadrant SCENES ('${DRIVER_SCENES[*]}') differ from quadrant_bench --list ('$known')"
  known="$("$BENCH" --engines quadrant:bogus 2>&1 | sed -n 's/.*(known: \([^)]*\)).*/\1/p' | sed 's/, / /g')"
  [[ "$known" == "${DRIVER_VARIANT_TOKENS[*]}" ]] || fail "tools/quadrant VARIANT_TOKENS ('${DRIVER_VARIANT_TOKENS[*]}') differ from the adapter's ('$known')"
  known="$("$HARDCASES" --help | sed -n 's/.*--cases a,b .*cases from \(.*\) (default all)$/\1/p' | sed 's/, / /g')"
  [[ "$known" == "${DRIVER_HARDCASES[*]}" ]] || fail "tools/quadrant HARDCASES differ from quadrant_hardcases --help ('$known')"
  known="$("$VALIDATE" --help | sed -n 's/.*--cases a,b .*cases from \(.*\) (default all)$/\1/p' | sed 's/, / /g')"
  [[ "$known" == "${DRIVER_VALIDATION_CASES[*]}" ]] || fail "tools/quadrant VALIDATION_CASES differ from quadrant_validate --help ('$known')"
  local engine most
  for engine in "${!DRIVER_ENGINE_MAX_THREADS[@]}"; do
    most="${DRIVER_ENGINE_MAX_THREADS[$engine]}"
    "$BENCH" --engines "$engine" --scenes circle_stress --counts 10 --threads "$most" --benchmark_list_tests=true \
      >/dev/null 2>&1 || fail "quadrant_bench does not run $engine at $most threads (ENGINE_MAX_THREADS)"
    ((most >= 64)) && continue
    grep -q "nothing to run" <<<"$("$BENCH" --engines "$engine" --scenes circle_stress --counts 10 --threads "$((most + 1))" 2>&1)" ||
      fail "quadrant_bench runs $engine at $((most + 1)) threads (ENGINE_MAX_THREADS says $most)"
  done
  for engine in "${!DRIVER_ENGINE_REFUSES_SCENE[@]}"; do
    grep -q "nothing to run" <<<"$("$BENCH" --engines "$engine" --scenes "${DRIVER_ENGINE_REFUSES_SCENE[$engine]}" --counts 10 --threads 1 2>&1)" ||
      fail "quadrant_bench runs $engine on ${DRIVER_ENGINE_REFUSES_SCENE[$engine]} (ENGINE_REFUSES_SCENE)"
  done
  echo "ok: the driver's scenes, variant tokens, case names and engine limits match the programs'"

  # Chipmunk's banner (stdout) and 3-line warnings (stderr) are one summary line; its errors and
  # everything else pass.
  local bins="$WORK/fake-bin" out="$WORK/filtered"
  mkdir -p "$bins"
  cat >"$bins/quadrant_hardcases" <<'SH'
#!/bin/sh
out="$2"
echo "Initializing cpSpace - Chipmunk v7.0.3 (Debug Enabled)"
echo "Compile with -DNDEBUG defined to disable debug mode and runtime assertion checks"
for i in 1 2 3; do
  printf 'Chipmunk warning: High EPA iterations: 3%s\n\tFailed condition: iteration < WARN_EPA_ITERATIONS\n\tSource:/build/chipmunk/src/cpCollision.c:340\n' "$i" >&2
done
printf 'Chipmunk warning: High GJK->EPA iterations: 9\n\tFailed condition: x\n\tSource:y.c:1\n' >&2
echo "the report's own line" >&2
echo "# Hard cases"
printf 'Aborting due to Chipmunk error: kept\n\tFailed condition: kept too\n' >&2
mkdir -p "$out" && echo '{}' >"$out/hardcases.json" && echo "# Hard cases" >"$out/hardcases.md"
SH
  chmod +x "$bins/quadrant_hardcases"
  status=0
  QUADRANT_BIN_DIR="$bins" "$DRIVER" hardcases --out "$out" >"$WORK/stdout" 2>"$WORK/stderr" || status=$?
  ((status == 0)) || fail "hardcases through the filter: exit $status: $(cat "$WORK/stderr")"
  ! grep -qE "Chipmunk warning|Failed condition: iteration|^Initializing cpSpace|Compile with -DNDEBUG" "$WORK/stdout" "$WORK/stderr" ||
    fail "Chipmunk's noise reached the log: $(cat "$WORK/stdout" "$WORK/stderr")"
  [[ "$(grep -c "Chipmunk (Debian's debug build) printed 4 warning(s) from inside its steps (3 x High EPA iterations, 1 x High GJK->EPA iterations; 3 lines each)" "$WORK/stderr")" == 1 ]] ||
    fail "no one summary line for Chipmunk's warnings: $(cat "$WORK/stderr")"
  grep -q "the report's own line" "$WORK/stderr" && grep -q "^# Hard cases" "$WORK/stdout" &&
    grep -q "Aborting due to Chipmunk error: kept" "$WORK/stderr" && grep -q "Failed condition: kept too" "$WORK/stderr" ||
    fail "the filter dropped other output: $(cat "$WORK/stdout" "$WORK/stderr")"
  echo "ok: Chipmunk's banner and warnings are one line: $(grep Chipmunk "$WORK/stderr" | head -1)"
}
first_hour
# ---- end of the first hour ------------------------------------------------------------------------

((failures == 0)) || { echo "$failures failure(s)"; exit 1; }
echo "all command-line refusals are one line, exit 2, outputs untouched"
