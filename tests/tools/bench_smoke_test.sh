#!/usr/bin/env bash
# Smoke test of the benchmark pipeline: quadrant_bench on a tiny configuration (both stress
# scenes, every engine, 50 bodies, 1 and 2 threads, 2 + 5 steps, 1 repetition), then
# bench_report.py --check on its JSON, then the report, whose files must exist and be non-empty;
# then a frame loop (--frame-rate), whose rows time the steps only.
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

echo "== bench_report.py --busy (busy machine table, noise flags)"
# A copy of the run as if made with --busy 1, one benchmark given a second repetition three
# times slower (a 200 % spread): the report must add the busy table and flag that benchmark.
"$PYTHON" - "$TMP/bench.json" "$TMP/bench_busy.json" <<'PY'
import copy, json, sys
d = json.load(open(sys.argv[1]))
d["context"]["busy_processes"] = "1"
row = next(r for r in d["benchmarks"] if r["name"].startswith("circle_stress/quadrant/n:50/threads:2"))
slow = copy.deepcopy(row)
slow["real_time"] *= 3
slow["steps_per_second"] /= 3
d["benchmarks"].append(slow)
json.dump(d, open(sys.argv[2], "w"))
PY
"$PYTHON" "$TOOLS/bench_report.py" "$TMP/bench.json" --busy "$TMP/bench_busy.json" --out "$TMP" >"$TMP/report.txt" \
  || fail "report with --busy failed"
grep -q "^## Busy machine (1 busy process" "$TMP/speedup.md" || fail "speedup.md has no busy machine table"
grep -q "^- \`circle_stress/quadrant/n:50/threads:2\`: repetitions spread" "$TMP/speedup.md" \
  || fail "the 200 % spread is not flagged"
grep -q "circle_stress | 50 | Quadrant | .*(\*\*noisy\*\*)" "$TMP/speedup.md" || fail "no noisy mark in the busy table"

echo "== quadrant_bench --frame-rate (a frame loop: each step then a sleep to the next frame)"
# 500 Hz (2 ms frames), 2 + 5 steps: only the steps are timed (manual time), so a step's time
# stays far below its frame; the context says the rate, every row has late_frames.
QUADRANT_COMMIT=smoke-test QUADRANT_MACHINE=smoke-test "$BENCH" \
  --scenes circle_stress --engines quadrant --counts 50 --threads 1,2 --steps 5 --warmup 2 --frame-rate 500 \
  --benchmark_out="$TMP/frames.json" --benchmark_out_format=json >/dev/null \
  || fail "quadrant_bench --frame-rate exited with status $?"
"$PYTHON" "$TOOLS/bench_report.py" --check "$TMP/frames.json" || fail "frame loop JSON check failed"
"$PYTHON" - "$TMP/frames.json" <<'PY' || fail "frame loop JSON: see above"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["context"]["frame_rate"] == "500", d["context"].get("frame_rate")
rows = [r for r in d["benchmarks"] if r.get("run_type") == "iteration"]
assert len(rows) == 2, [r["name"] for r in rows]
for r in rows:
    assert r["name"].endswith("/manual_time"), r["name"]
    assert "late_frames" in r, r
    # 5 steps of 50 circles take well under 5 frames of 2 ms: the sleeps are not timed.
    assert r["ms_per_step"] < 2.0, r["ms_per_step"]
    assert abs(r["real_time"] - 5 * r["ms_per_step"]) <= 1e-6 * r["real_time"] + 1e-9, (r["real_time"], r["ms_per_step"])
print("frame loop rows:", ", ".join(f'{r["name"]} {r["ms_per_step"]:.4f} ms/step' for r in rows))
PY
"$PYTHON" "$TOOLS/bench_report.py" "$TMP/frames.json" --out "$TMP/frames" >/dev/null || fail "frame loop report failed"
grep -q "frame loop" "$TMP/frames/speedup.md" || fail "speedup.md does not say it is a frame loop"

echo "PASS"
