#!/bin/bash
# The distributed world on the lent 16-core machine, in one go (about 2.5 minutes): the pool's
# cost per stage at 1-16 threads (quadrant_task_overhead -> $OUT/task_overhead.json), weak scaling at
# 1-16 ranks (with R independent one-rank worlds beside each, the machine's ceiling) and ranks x
# threads on 16 cores (issue #30). tools/device_pack_mpi.sh copies it to .device/distributed.sh;
# run from the project root after .device/scaling.sh, carrying .device. Writes
# $OUT/distributed.jsonl (quadrant_distributed's JSON, one run a line, each with its ranks and threads) and
# appends its progress to $OUT/log.txt. The report: tools/distributed_report.py distributed.jsonl
# --machine M --commit C --json distributed.json --md distributed.md (as for bench --ranks).
set -u
D=$(pwd)/.device
export LD_LIBRARY_PATH=$D/lib
export OPAL_PREFIX=$D/mpi PMIX_INSTALL_PREFIX=$D/mpi/pmix PMIX_MCA_mca_base_component_path=$D/mpi/pmix/lib/pmix PATH=$D/mpi/bin:$PATH
export OMPI_MCA_mca_base_component_show_load_errors=0 OMPI_MCA_btl=self,vader OMPI_MCA_pml=ob1
O=${OUT:-/tmp/out}; mkdir -p "$O"
J=$O/distributed.jsonl
CORES=$(nproc)
STEPS=${STEPS:-200}
run() {  # RANKS THREADS ARGS...: one quadrant_distributed run, each rank on THREADS cores of its own
  local r=$1 t=$2; shift 2
  ((r * t <= CORES)) || return 0
  echo "== distributed -np $r --threads $t $* $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> "$O/log.txt"
  timeout 120 "$D/mpi/bin/mpirun" --allow-run-as-root --map-by "slot:PE=$t" --bind-to core -np "$r" \
    "$D/quadrant_distributed" --threads "$t" --steps "$STEPS" --warmup 50 "$@" >> "$J" 2>> "$O/log.txt"
  echo "== rc $? $(date -u +%T)" >> "$O/log.txt"
}
: > "$J"
# First, the pool's cost per parallel-for and per stage of a region at 1-16 threads, against
# OpenMP (quadrant_task_overhead; about 20 s): what a barrier costs on real cores (issue #25).
echo "== task_overhead $(date -u +%T) load $(cut -d' ' -f1-3 /proc/loadavg)" >> "$O/log.txt"
timeout 120 "$D/quadrant_task_overhead" --benchmark_out="$O/task_overhead.json" --benchmark_out_format=json \
  --benchmark_repetitions=3 --benchmark_report_aggregates_only=true >> "$O/log.txt" 2>&1
echo "== rc $? $(date -u +%T)" >> "$O/log.txt"
for scene in "circle_stress --count 16000" "many_pyramids --count 2750"; do
  for r in 1 2 4 8 16; do
    if [ "$r" -eq 1 ]; then
      # shellcheck disable=SC2086  # $scene is a list of words
      run 1 1 --solver soft_step --scene $scene --per-rank --world
    else
      # shellcheck disable=SC2086
      run "$r" 1 --solver soft_step --scene $scene --per-rank
      # shellcheck disable=SC2086
      run "$r" 1 --solver soft_step --scene $scene --per-rank --independent
    fi
  done
done
# Ranks x threads on all the cores, strong scaling; one rank with --world also times the World at
# 16 threads on the same scene.
for scene in "circle_stress --count 64000" "many_pyramids --count 22000"; do
  for rt in "1 16" "2 8" "4 4" "8 2" "16 1"; do
    r=${rt% *} t=${rt#* } world=()
    [ "$r" -eq 1 ] && world=(--world)
    # shellcheck disable=SC2086
    run "$r" "$t" --solver soft_step --scene $scene "${world[@]}"
  done
done
echo "distributed done $(date -u +%T)" >> "$O/log.txt"
