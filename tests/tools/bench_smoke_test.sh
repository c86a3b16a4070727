#!/usr/bin/env bash
# Smoke test of the benchmark pipeline: quadrant_bench on a tiny configuration (both stress
# scenes, every engine, 50 bodies, 1 and 2 threads, 2 + 5 steps, 1 repetition), then
# bench_report.py --check on its JSON, then the report, whose files must exist and be non-empty.
#
# usage: bench_smoke_test.sh <path to quadrant_bench> <tools dir>
set -euo pipefail

if (($# != 2)); then
  echo "usage: $0 <quadrant_bench> <tools dir>" >&2
  exit 2
fi
BENCH="$1"
TOOLS="$2"
PYTHON=/usr/bin/python3  # Debian's interpreter, which sees python3-matplotlib

[[ -x "$BENCH" ]] || { echo "FAIL: $BENCH is not an executable" >&2; exit 1; }
[[ -f "$TOOLS/bench_report.py" ]] || { echo "FAIL: $TOOLS/bench_report.py not found" >&2; exit 1; }

TMP="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-bench-smoke.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }

echo "== quadrant_bench (tiny configuration)"
QUADRANT_COMMIT=smoke-test QUADRANT_MACHINE=smoke-test "$BENCH" \
  --scenes circle_stress,polygon_stress --counts 50 --threads 1,2 --steps 5 --warmup 2 \
  --benchmark_repetitions=1 --benchmark_enable_random_interleaving=true \
  --benchmark_out="$TMP/bench.json" --benchmark_out_format=json \
  || fail "quadrant_bench exited with status $?"
[[ -s "$TMP/bench.json" ]] || fail "no JSON written"

echo "== bench_report.py --check"
"$PYTHON" "$TOOLS/bench_report.py" --check "$TMP/bench.json" || fail "JSON check failed"

# Every engine must appear at least once (at 1 thread), or be reported unsupported.
engines="$("$PYTHON" -c '
import json, sys
d = json.load(open(sys.argv[1]))
print(d["context"].get("engines", ""))' "$TMP/bench.json")"
[[ -n "$engines" ]] || fail "no engines in the JSON context"
for engine in ${engines//,/ }; do
  for scene in circle_stress polygon_stress; do
    name="$scene/$engine/n:50/threads:1"
    if ! grep -q "\"name\": \"$name/" "$TMP/bench.json" && ! grep -q "$name: " "$TMP/bench.json"; then
      fail "$name neither ran nor was reported unsupported"
    fi
  done
done

echo "== bench_report.py (report)"
"$PYTHON" "$TOOLS/bench_report.py" "$TMP/bench.json" --out "$TMP" >"$TMP/report.txt" \
  || fail "report generation failed"
for f in speedup.md fps_circle_stress.png fps_polygon_stress.png; do
  [[ -s "$TMP/$f" ]] || fail "$f missing or empty"
done
grep -q "circle_stress, N = 50" "$TMP/speedup.md" || fail "speedup.md has no circle_stress table"
grep -q "polygon_stress, N = 50" "$TMP/speedup.md" || fail "speedup.md has no polygon_stress table"

echo "PASS"
