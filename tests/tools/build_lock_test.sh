#!/usr/bin/env bash
# One build at a time per checkout (issue #29 item 6): in a temporary copy of the driver with a
# fake cmake (each configure or build logs its start and end and takes a second),
#  - two `tools/quadrant build` started together run one after the other, and the second says in
#    one line that it waits for the first (build/release.lock);
#  - `tools/quadrant hardcases` runs a copy of the program it built, not build/.../quadrant_hardcases,
#    so a build that relinks the program while it runs does not touch it; the build meanwhile
#    waits for nothing (the lock is not held while programs run).
# usage: build_lock_test.sh ROOT
set -uo pipefail
ROOT="$1"
WORK="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-build-lock-test.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

T="$WORK/checkout"
mkdir -p "$T/tools" "$WORK/bin"
cp "$ROOT/tools/quadrant" "$T/tools/"
cp "$ROOT/CMakePresets.json" "$T/"
LOG="$WORK/cmake.log"
# A fake cmake: "--preset P" configures (build.ninja, CMakeCache.txt), "--build --preset P
# [--target X...]" writes each target as a program under build/P/benchmarks/ that records the
# path it runs from, sleeps a little and writes the report files.
cat >"$WORK/bin/cmake" <<EOF
#!/usr/bin/env bash
echo "start \$\$ \$*" >>"$LOG"
# The very first cmake holds on until the test has seen the second build wait (or 30 s), so a
# loaded machine cannot let the second start after the first is done.
if mkdir "$WORK/first" 2>/dev/null; then
  for _ in \$(seq 300); do [[ -e "$WORK/go" ]] && break; sleep 0.1; done
fi
sleep 1
if [[ "\$1" == --build ]]; then
  preset="\$3"
  shift 3
  mkdir -p "$T/build/\$preset/benchmarks"
  while ((\$#)); do
    if [[ "\$1" == --target ]]; then
      shift
      for target in "\$@"; do
        cat >"$T/build/\$preset/benchmarks/\$target" <<'PROG'
#!/bin/sh
echo "\$0" >>"$WORK/ran"
sleep 2
mkdir -p "\$2" && echo '{}' >"\$2/hardcases.json" && echo "# Hard cases" >"\$2/hardcases.md"
PROG
        chmod +x "$T/build/\$preset/benchmarks/\$target"
      done
      break
    fi
    shift
  done
else
  mkdir -p "$T/build/\$2" && touch "$T/build/\$2/build.ninja" "$T/build/\$2/CMakeCache.txt"
fi
echo "end \$\$" >>"$LOG"
EOF
# Every Debian package installed, as far as setup can tell.
printf '#!/bin/sh\nprintf "install ok installed"\n' >"$WORK/bin/dpkg-query"
chmod +x "$WORK/bin/cmake" "$WORK/bin/dpkg-query"
export PATH="$WORK/bin:$PATH"
unset QUADRANT_BIN_DIR

# Two builds at once.
"$T/tools/quadrant" build >"$WORK/a.out" 2>"$WORK/a.err" &
a=$!
# The second once the first's cmake runs (it holds the lock then).
for _ in $(seq 100); do [[ -s "$LOG" ]] && break; sleep 0.1; done
"$T/tools/quadrant" build >"$WORK/b.out" 2>"$WORK/b.err" &
b=$!
for _ in $(seq 300); do [[ -s "$WORK/b.err" ]] && break; sleep 0.1; done
touch "$WORK/go"
wait "$a" || fail "the first build failed: $(cat "$WORK/a.err")"
wait "$b" || fail "the second build failed: $(cat "$WORK/b.err")"
# The log must alternate start/end: no cmake started while another ran.
pattern="$(awk '{ printf "%s ", $1 }' "$LOG")"
[[ "$pattern" == "start end start end start end " || "$pattern" == "start end start end " ]] ||
  fail "the builds overlapped: $(tr '\n' ';' <"$LOG")"
grep -q "^quadrant: waiting for another build of preset release in this checkout to finish (build/release.lock, held by pid [0-9]*: tools/quadrant build)$" "$WORK/b.err" ||
  fail "the second build did not say that it waits: $(cat "$WORK/b.err")"
[[ "$(wc -l <"$WORK/b.err")" == 1 ]] || fail "the second build printed more than its one waiting line: $(cat "$WORK/b.err")"
[[ -f "$T/build/release.lock" ]] || fail "no build/release.lock"
echo "ok: two builds serialized ($(tr '\n' ';' <"$LOG")); the second said: $(cat "$WORK/b.err")"

# A command runs a copy of what it built; a build meanwhile relinks the original only.
: >"$LOG"
"$T/tools/quadrant" hardcases --out "$WORK/out" >"$WORK/h.out" 2>"$WORK/h.err" &
h=$!
for _ in $(seq 50); do [[ -s "$WORK/ran" ]] && break; sleep 0.1; done
[[ -s "$WORK/ran" ]] || fail "hardcases did not start its program: $(cat "$WORK/h.err")"
"$T/tools/quadrant" build >"$WORK/c.out" 2>"$WORK/c.err" || fail "a build during hardcases failed: $(cat "$WORK/c.err")"
! grep -q "waiting" "$WORK/c.err" || fail "the build waited for a running program: $(cat "$WORK/c.err")"
wait "$h" || fail "hardcases failed: $(cat "$WORK/h.err")"
ran="$(cat "$WORK/ran")"
[[ "$ran" != "$T/build/"* && "$ran" == */quadrant_hardcases ]] || fail "hardcases ran $ran, not a copy"
[[ ! -e "$ran" ]] || fail "the copy $ran was not removed when the driver ended"
[[ -s "$WORK/out/hardcases.md" ]] || fail "hardcases wrote no report: $(cat "$WORK/h.err")"
echo "ok: hardcases ran a copy ($ran) while a build ran beside it"

((failures == 0)) || { echo "$failures failure(s)"; exit 1; }
echo "PASS"
