#!/usr/bin/env bash
# tools/compare_commits.sh: the standard interleaved comparison of two quadrant_bench builds, the
# one the README's "Results" tables quote (issues #13 and #14):
#
#   tools/compare_commits.sh OLD_BENCH NEW_BENCH OUT_DIR [--rounds R] [--only SET,...]
#
# Sets (all by default), each `tools/interleave.sh` of R rounds (default 9) into OUT_DIR/SET and
# `tools/quadrant compare` into OUT_DIR/SET.md:
#   pyramid       base-100 pyramid (5050 boxes), 1 and 2 threads, 60 steps after 10
#   stress        circle and polygon stress at 16000, 1 and 2 threads, 60 steps after 10
#   small         both stress scenes at 1000, 1 and 2 threads, 200 steps after 20
#   busy_pyramid  the pyramid at 1-4 threads (3 and 4 oversubscribed) beside one busy loop, 30 steps after 10
#   busy_stress   circle stress 16000 at 1-4 threads beside one busy loop, 60 steps after 10
# The busy loop (`bash -c 'while :; do :; done'`) is this script's own: started before the busy
# sets and stopped by its process id when they end or the script fails (OUT_DIR/busy.txt says
# which). A set that fails leaves the sets before it as they were; a set's directory is replaced
# only once its run succeeded (it runs into OUT_DIR/.SET.tmp first).
# OUT_DIR belongs outside results/ (e.g. runs/<machine>/vs_<commit>/, which git ignores): the raw
# rounds are not committed; a comparison worth keeping goes into results/<machine>/comparisons.md
# as its section (what was compared, this command, the SET.md tables and load.txt as written).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
usage() { echo "usage: tools/compare_commits.sh OLD_BENCH NEW_BENCH OUT_DIR [--rounds R] [--only SET,...]" >&2; exit 2; }
(($# >= 3)) || usage
old="$1" new="$2" out="$3"; shift 3
rounds=9 only="pyramid,stress,small,busy_pyramid,busy_stress"
while (($#)); do
  case "$1" in
    --rounds) [[ $# -ge 2 && "$2" =~ ^[1-9][0-9]*$ ]] || { echo "compare_commits: --rounds needs a positive integer" >&2; exit 2; }
              rounds="$2"; shift 2 ;;
    --only) [[ $# -ge 2 ]] || usage; only="$2"; shift 2 ;;
    *) echo "compare_commits: unknown option '$1'" >&2; usage ;;
  esac
done
[[ -x "$old" && -x "$new" ]] || { echo "compare_commits: OLD_BENCH and NEW_BENCH must be executables" >&2; exit 2; }
IFS=, read -r -a sets <<<"$only"
for s in "${sets[@]}"; do
  case "$s" in pyramid|stress|small|busy_pyramid|busy_stress) ;; *) echo "compare_commits: unknown set '$s'" >&2; exit 2 ;; esac
done
mkdir -p "$out"

busy_pid=""
stop_busy() { [[ -n "$busy_pid" ]] && kill "$busy_pid" 2>/dev/null && wait "$busy_pid" 2>/dev/null; busy_pid=""; }
trap stop_busy EXIT

run_set() {  # run_set NAME bench-args...
  local name="$1"; shift
  local tmp="$out/.$name.tmp"
  rm -rf "$tmp"
  "$ROOT/tools/interleave.sh" "$old" "$new" "$tmp" "$rounds" "$@"
  rm -rf "${out:?}/$name" && mv "$tmp" "$out/$name"
  # The busy sets are loaded on purpose, both sides alike (interleaved rounds): compare gives their
  # verdicts, marked (loaded), instead of withholding them.
  local load=()
  [[ "$name" != busy_* ]] || load=(--allow-load)
  # exits 1 when something is slower, 4 when a quiet set ran loaded
  "$ROOT/tools/quadrant" compare "$out/$name/old" "$out/$name/new" "${load[@]}" >"$out/$name.md" || true
  echo "compare_commits: $name -> $out/$name.md"
}

for s in "${sets[@]}"; do
  case "$s" in
    pyramid) stop_busy; run_set pyramid --scenes pyramid --counts 5050 --engines quadrant --threads 1,2 --steps 60 --warmup 10 ;;
    stress) stop_busy; run_set stress --scenes circle_stress,polygon_stress --counts 16000 --engines quadrant --threads 1,2 --steps 60 --warmup 10 ;;
    small) stop_busy; run_set small --scenes circle_stress,polygon_stress --counts 1000 --engines quadrant --threads 1,2 --steps 200 --warmup 20 ;;
    busy_pyramid|busy_stress)
      if [[ -z "$busy_pid" ]]; then
        bash -c 'while :; do :; done' &
        busy_pid=$!
        echo "busy loop: pid $busy_pid (bash -c 'while :; do :; done'), started before $s, stopped by its pid after the busy sets" >"$out/busy.txt"
      fi
      if [[ $s == busy_pyramid ]]; then
        run_set busy_pyramid --scenes pyramid --counts 5050 --engines quadrant --threads 1,2,3,4 --steps 30 --warmup 10
      else
        run_set busy_stress --scenes circle_stress --counts 16000 --engines quadrant --threads 1,2,3,4 --steps 60 --warmup 10
      fi ;;
  esac
done
stop_busy
