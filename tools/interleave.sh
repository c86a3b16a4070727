#!/usr/bin/env bash
# tools/interleave.sh: two quadrant_bench builds measured as alternating processes, so that a
# machine's drift hits both alike (the noise here is 10-30 % over minutes).
#
#   tools/interleave.sh OLD_BENCH NEW_BENCH OUT_DIR ROUNDS [quadrant_bench arguments...]
#
# Each round runs OLD then NEW once with the given arguments and one repetition, writing
# OUT_DIR/old/rK.json and OUT_DIR/new/rK.json; `tools/quadrant compare OUT_DIR/old OUT_DIR/new`
# then pools the rounds (9 rounds: enough repetitions for its test). The load average before
# and after is written to OUT_DIR/load.txt.
set -euo pipefail
(($# >= 4)) || { echo "usage: tools/interleave.sh OLD_BENCH NEW_BENCH OUT_DIR ROUNDS [bench args...]" >&2; exit 2; }
old="$1" new="$2" out="$3" rounds="$4"; shift 4
[[ -x "$old" && -x "$new" ]] || { echo "interleave: OLD_BENCH and NEW_BENCH must be executables" >&2; exit 2; }
[[ "$rounds" =~ ^[1-9][0-9]*$ ]] || { echo "interleave: ROUNDS must be a positive integer (got '$rounds')" >&2; exit 2; }
mkdir -p "$out/old" "$out/new"
echo "before: $(cat /proc/loadavg)" >"$out/load.txt"
for ((r = 1; r <= rounds; ++r)); do
  for side in old new; do
    bin="$old"; [[ $side == new ]] && bin="$new"
    "$bin" "$@" --benchmark_repetitions=1 --benchmark_out="$out/$side/r$r.json" \
      --benchmark_out_format=json >/dev/null 2>&1 || { echo "interleave: $side run $r failed" >&2; exit 1; }
  done
done
echo "after: $(cat /proc/loadavg)" >>"$out/load.txt"
