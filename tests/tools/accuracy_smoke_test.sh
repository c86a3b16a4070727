#!/usr/bin/env bash
# Smoke test of `tools/quadrant accuracy` and `tools/quadrant effects`: both programs with --quick
# into a temporary directory, then the JSON structure checks of tools/accuracy_report.py, then
# the accuracy report, whose Markdown and plot must exist and hold what the command promises.
#
# usage: accuracy_smoke_test.sh <quadrant_accuracy> <quadrant_effects> <tools dir>
set -euo pipefail

if (($# != 3)); then
  echo "usage: $0 <quadrant_accuracy> <quadrant_effects> <tools dir>" >&2
  exit 2
fi
ACCURACY="$1"
EFFECTS="$2"
TOOLS="$3"
PYTHON=/usr/bin/python3  # Debian's interpreter, which sees python3-matplotlib

fail() { echo "FAIL: $*" >&2; exit 1; }
[[ -x "$ACCURACY" ]] || fail "$ACCURACY is not an executable"
[[ -x "$EFFECTS" ]] || fail "$EFFECTS is not an executable"
[[ -f "$TOOLS/accuracy_report.py" ]] || fail "$TOOLS/accuracy_report.py not found"

TMP="$(mktemp -d "${TMPDIR:-/tmp}/quadrant-accuracy-smoke.XXXXXX")"
trap 'rm -rf "$TMP"' EXIT
export QUADRANT_COMMIT=smoke-test QUADRANT_MACHINE=smoke-test

echo "== quadrant_accuracy --quick"
"$ACCURACY" --out "$TMP" --quick || fail "quadrant_accuracy exited with status $?"
[[ -s "$TMP/accuracy.json" ]] || fail "no accuracy.json written"
"$PYTHON" "$TOOLS/accuracy_report.py" check "$TMP/accuracy.json" || fail "accuracy.json structure check failed"

# The sweep's promises: every quick setting on every scene, the peers included, and a hard-case
# verdict for every Quadrant setting of the quick list on each quick case.
"$PYTHON" - "$TMP/accuracy.json" <<'EOF' || fail "accuracy.json content check failed"
import json, sys
d = json.load(open(sys.argv[1]))
runs = d["runs"]
scenes = {"vertical_stack", "pyramid", "mass_ratio_100", "mass_ratio_400", "tall_stack", "heavy_on_supports",
          "heavy_on_slab", "circle_stress", "polygon_stress"}
engines = {"quadrant", "box2d", "bullet", "chipmunk"}
assert {r["scene"] for r in runs} == scenes, {r["scene"] for r in runs}
assert {r["engine"] for r in runs} == engines, {r["engine"] for r in runs}
solvers = {r["solver"] for r in runs if r["engine"] == "quadrant"}
assert solvers == {"thesis", "pgs", "soft_step"}, solvers
for r in runs:
    assert r["precision"] == d["context"]["precision"]
    if "unsupported" not in r:
        assert len(r["ms_samples"]) == d["context"]["repetitions"], r
pile = [r for r in runs if r["scene"] == "pyramid" and r["id"] == "quadrant:pgs+it8"][0]
assert pile["errors"]["finite"] is True and pile["errors"]["max_penetration_m"] >= 0, pile
stress = [r for r in runs if r["scene"] == "circle_stress" and r["id"] == "quadrant:pgs+it8"][0]
assert abs(stress["errors"]["ke_drift"]) < 1, stress
hard = d["hard_cases"]
quadrant_ids = {r["id"] for r in runs if r["engine"] == "quadrant"}
for case in ("vertical_stack", "mass_ratio_400"):
    got = {h["id"] for h in hard if h["scene"] == case and h["engine"] == "quadrant"}
    assert got == quadrant_ids, (case, got)
print("content ok: {} runs, {} hard-case verdicts".format(len(runs), len(hard)))
EOF

echo "== accuracy_report.py report"
"$PYTHON" "$TOOLS/accuracy_report.py" report "$TMP/accuracy.json" --out "$TMP" >/dev/null \
  || fail "report generation failed"
for f in accuracy.md accuracy.png; do
  [[ -s "$TMP/$f" ]] || fail "$f missing or empty"
done
grep -q "## pyramid" "$TMP/accuracy.md" || fail "accuracy.md has no pyramid table"
grep -q "cheapest setting that meets each hard-case criterion" "$TMP/accuracy.md" \
  || fail "accuracy.md has no hard-case section"

echo "== quadrant_effects --quick"
"$EFFECTS" --out "$TMP" --quick >/dev/null || fail "quadrant_effects exited with status $?"
[[ -s "$TMP/effects.json" && -s "$TMP/effects.md" ]] || fail "effects.json or effects.md missing"
"$PYTHON" "$TOOLS/accuracy_report.py" check-effects "$TMP/effects.json" || fail "effects.json structure check failed"

echo "PASS"
