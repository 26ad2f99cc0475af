#!/bin/bash
# Times LIGGGHTS on the 2000-sphere 3D heap (bench/liggghts-heap.in) for the
# side-by-side speed comparison with `repose bench --heap`: the pour into the
# empty box (60 000 steps) and the heap at rest (30 000 steps, after 60 000
# untimed settling steps), one process and one thread at a time. Writes
# throughput_liggghts.csv, which `repose bench --heap --liggghts` reads.
#
#   apt-get install -y liggghts
#   bench/liggghts-heap.sh                       # 3 trials of each phase
#   NTRIAL=1 SCALE=0.05 bench/liggghts-heap.sh   # quick check of the whole chain
#   repose bench --heap --liggghts out/liggghts/throughput_liggghts.csv
#
# Environment: LIGGGHTS (the program, default `liggghts` as Debian installs
# it), OUT (output folder, default out/liggghts in the repository), NTRIAL
# (trials per phase, default 3), SCALE (factor on all step counts, default
# 1), ROLLING (rolling-friction models to run, default "epsd2", the one repose
# compares against; "epsd2 cdt" adds LIGGGHTS's constant directional torque).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
INPUT=$ROOT/bench/liggghts-heap.in
LIGGGHTS=${LIGGGHTS:-liggghts}
OUT=${OUT:-$ROOT/out/liggghts}
NTRIAL=${NTRIAL:-3}
SCALE=${SCALE:-1}
ROLLING=${ROLLING:-epsd2}
export OMP_NUM_THREADS=1

if ! command -v "$LIGGGHTS" > /dev/null; then
  echo "LIGGGHTS not found as '$LIGGGHTS': apt-get install -y liggghts, or set LIGGGHTS" >&2
  exit 1
fi
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
CSV=$OUT/throughput_liggghts.csv

scaled() { awk -v n="$1" -v f="$SCALE" 'BEGIN { m = int(n * f + 0.5); print (m < 1 ? 1 : m) }'; }
NPOUR=$(scaled 60000)
NSETTLE=$(scaled 60000)
NSETTLED=$(scaled 30000)

# One LIGGGHTS process for a stage; its screen output goes to a file (this
# build crashes while inserting grains when told to print nothing).
heap() {
  local stage=$1 rolling=$2 dir=$3 log=$4
  "$LIGGGHTS" -in "$INPUT" -log "$log" -var stage "$stage" -var rolling "$rolling" \
    -var dir "$dir" -var npour "$NPOUR" -var nsettle "$NSETTLE" -var nsettled "$NSETTLED" \
    < /dev/null > "${log%.log}.screen" 2>&1 \
    || { echo "LIGGGHTS failed, see $log" >&2; exit 1; }
}

# From a run's log: grains at the start and end, particle-steps and the loop
# time. Grains enter right after a thermo line (both every 500 steps), so the
# count printed at the end of an interval held for all of its steps.
read_log() {
  awk '
    /^ *Step +Atoms/ { inrun = 1; first = 1; next }
    /^Loop time of/  { inrun = 0; loop = $4; next }
    inrun && $1 ~ /^[0-9]+$/ {
      if (first) start = $2
      else       work += $2 * ($1 - s)
      s = $1; last = $2; first = 0
    }
    END { printf "%d %d %.0f %.6g\n", start, last, work, loop }
  ' "$1"
}

# Times one stage and appends its row to the CSV.
timed() {
  local phase=$1 stage=$2 rolling=$3 dir=$4 trial=$5 steps=$6
  local log=$dir/$phase-$trial.log t0 t1 n0 n1 work loop
  t0=$EPOCHREALTIME
  heap "$stage" "$rolling" "$dir" "$log"
  t1=$EPOCHREALTIME
  read -r n0 n1 work loop < <(read_log "$log")
  awk -v OFS=, -v csv="$CSV" -v rf="$rolling" -v ph="$phase" -v st="$steps" -v tr="$trial" \
      -v n0="$n0" -v n1="$n1" -v work="$work" -v loop="$loop" -v t0="$t0" -v t1="$t1" 'BEGIN {
    real = t1 - t0
    print "3D_heap_2000", rf, ph, st, tr, n0, n1, work, sprintf("%.3f", real), loop,
          sprintf("%.4g", work / real), sprintf("%.4g", work / loop) >> csv
    printf "%-5s %-7s trial %s: %d -> %d grains, %d steps, %.2f M particle-steps/s (wall), %.2f M (loop)\n",
           rf, ph, tr, n0, n1, st, work / real / 1e6, work / loop / 1e6
  }'
}

echo "scene,rolling,phase,nsteps,trial,N_start,N_end,atom_steps,real_s,loop_s,psteps_per_s_real,psteps_per_s_loop" > "$CSV"
for rolling in $ROLLING; do
  dir=$OUT/$rolling
  mkdir -p "$dir"
  for trial in $(seq 1 "$NTRIAL"); do
    timed pour pour "$rolling" "$dir" "$trial" "$NPOUR"
  done
  echo "$rolling: settling the heap for $NSETTLE steps (not timed) ..."
  heap settle "$rolling" "$dir" "$dir/settle.log"
  for trial in $(seq 1 "$NTRIAL"); do
    timed settled settled "$rolling" "$dir" "$trial" "$NSETTLED"
  done
done
echo "wrote $CSV"
