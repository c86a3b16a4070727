#!/usr/bin/env bash
# Test of the instruction-count check (tools/icount.py): it must pass for the binary the counts
# were taken from and fail for one that does more work per step.
#
# Builds quadrant_icount in its own build directory twice: normally, then with
# QUADRANT_ICOUNT_INJECT_EXTRA_WORK=ON (a deliberate extra pass over the bodies every step).
# Both builds share one directory, reconfigured in between: the option only changes
# quadrant_icount's own compile definitions, so the second build recompiles one file instead of
# the engine and adapters again. The directory stays under the build tree, so later runs are
# incremental. Then, with a temporary icount.json made by --update from the normal binary (the
# committed results/icount.json is never touched; the test checks that too):
#   --check on the normal binary   -> exit 0
#   --check on the injected binary -> exit 1, reporting MORE WORK
#   --check against counts recorded by another compiler -> exit 2 (refused)
#   --update from the injected binary -> exit 2 (refused)
#
# usage: icount_test.sh <source dir> <work dir> <CMake generator> <C++ compiler>
set -euo pipefail

if (($# != 4)); then
  echo "usage: $0 <source dir> <work dir> <generator> <c++ compiler>" >&2
  exit 2
fi
SRC="$1"
WORK="$2"
GENERATOR="$3"
CXX_COMPILER="$4"
PYTHON=/usr/bin/python3  # Debian's interpreter
ICOUNT="$SRC/tools/icount.py"
JOBS=2

fail() { echo "FAIL: $*" >&2; exit 1; }

command -v valgrind >/dev/null || fail "valgrind not found (tools/quadrant setup installs it)"
[[ -f "$ICOUNT" ]] || fail "$ICOUNT not found"

BUILD="$WORK/build"
TMP="$WORK/tmp"
rm -rf "$TMP"
mkdir -p "$BUILD" "$TMP"
COMMITTED="$SRC/results/icount.json"
committed_before="$(md5sum "$COMMITTED" 2>/dev/null || echo absent)"

# build_icount ON|OFF DEST: configures and builds quadrant_icount with the option, copies it.
build_icount() {
  local inject="$1" dest="$2"
  echo "== build quadrant_icount with QUADRANT_ICOUNT_INJECT_EXTRA_WORK=$inject"
  cmake -S "$SRC" -B "$BUILD" -G "$GENERATOR" -DCMAKE_CXX_COMPILER="$CXX_COMPILER" \
    -DCMAKE_BUILD_TYPE=Release -DQUADRANT_BUILD_TESTS=OFF -DQUADRANT_BUILD_BENCHMARKS=ON \
    -DQUADRANT_ICOUNT_INJECT_EXTRA_WORK="$inject" >"$TMP/configure-$inject.log" 2>&1 \
    || { cat "$TMP/configure-$inject.log" >&2; fail "configure ($inject) failed"; }
  cmake --build "$BUILD" -j "$JOBS" --target quadrant_icount || fail "build ($inject) failed"
  cp "$BUILD/benchmarks/quadrant_icount" "$dest"
  grep -qx "extra_work=$([[ $inject == ON ]] && echo 1 || echo 0)" <("$dest" --info) \
    || fail "$dest --info does not report extra_work for $inject"
}

build_icount OFF "$TMP/quadrant_icount.normal"
build_icount ON "$TMP/quadrant_icount.extra"

JSON="$TMP/icount.json"

echo "== icount.py --update (normal binary, temporary json)"
"$PYTHON" "$ICOUNT" --update --binary "$TMP/quadrant_icount.normal" --json "$JSON" \
  || fail "--update exited with $?"
[[ -s "$JSON" ]] || fail "--update wrote no $JSON"

echo "== icount.py --check (normal binary): must pass"
status=0
"$PYTHON" "$ICOUNT" --check --binary "$TMP/quadrant_icount.normal" --json "$JSON" \
  >"$TMP/check-normal.txt" || status=$?
cat "$TMP/check-normal.txt"
((status == 0)) || fail "--check on the normal binary exited $status (expected 0)"

echo "== icount.py --check (injected extra work): must fail with exit 1"
status=0
"$PYTHON" "$ICOUNT" --check --binary "$TMP/quadrant_icount.extra" --json "$JSON" \
  >"$TMP/check-extra.txt" || status=$?
cat "$TMP/check-extra.txt"
((status == 1)) || fail "--check on the injected binary exited $status (expected 1)"
grep -q "MORE WORK" "$TMP/check-extra.txt" || fail "no scene reported as MORE WORK"
# Every scene must show the extra work by more than 5 % (the injection is meant to be obvious).
"$PYTHON" - "$TMP/check-extra.txt" <<'EOF' || fail "the injected work is not > 5 % on every scene"
import re, sys
changes = [float(m) for m in re.findall(r"\| ([+-][0-9.]+) % \|", open(sys.argv[1]).read())]
print("changes (%):", changes)
sys.exit(0 if changes and all(c > 5 for c in changes) else 1)
EOF

echo "== icount.py --check against counts of another compiler: must refuse with exit 2"
"$PYTHON" -c '
import json, sys
d = json.load(open(sys.argv[1])); d["compiler"] = "GCC 0.0.1 (another compiler)"
json.dump(d, open(sys.argv[2], "w"))' "$JSON" "$TMP/other-compiler.json"
status=0
"$PYTHON" "$ICOUNT" --check --binary "$TMP/quadrant_icount.normal" --json "$TMP/other-compiler.json" \
  2>"$TMP/other-compiler.err" || status=$?
cat "$TMP/other-compiler.err" >&2
((status == 2)) || fail "--check with another compiler's counts exited $status (expected 2)"
grep -q "not comparable" "$TMP/other-compiler.err" || fail "no clear message about the compiler"

echo "== icount.py --update from the injected binary: must refuse with exit 2"
status=0
"$PYTHON" "$ICOUNT" --update --binary "$TMP/quadrant_icount.extra" --json "$TMP/never.json" \
  2>/dev/null || status=$?
((status == 2)) || fail "--update from the injected binary exited $status (expected 2)"
[[ ! -e "$TMP/never.json" ]] || fail "--update from the injected binary wrote a file"

[[ "$(md5sum "$COMMITTED" 2>/dev/null || echo absent)" == "$committed_before" ]] \
  || fail "the committed $COMMITTED changed during the test"
rm -rf "$TMP"
echo "PASS"
