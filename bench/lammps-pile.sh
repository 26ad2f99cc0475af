#!/bin/bash
# Times LAMMPS on the 2D fill-and-release pile (bench/lammps-pile.in) for the
# side-by-side speed comparison with `repose bench`: the W = H = 4 (400
# grains) and W = H = 8 (1600 grains) piles, at rest in the closed box and
# spilling after the right wall is removed, one process and one thread at a
# time. Writes throughput_lammps.csv, which `repose bench --lammps` reads.
#
#   apt-get install -y lammps
#   bench/lammps-pile.sh                       # 3 trials of each, a few minutes
#   NTRIAL=1 SCALE=0.05 bench/lammps-pile.sh   # quick check of the whole chain
#   repose bench --lammps out/lammps/throughput_lammps.csv
#
# Environment: LMP (LAMMPS program, default `lmp` as Debian installs it),
# OUT (output folder, default out/lammps in the repository), NTRIAL (trials
# per phase, default 3), SCALE (factor on the timed step counts, default 1),
# SIZES (box sizes W = H, default "4 8"). The settled piles are kept in
# OUT/W<size>/settled.restart and reused; delete them to fill anew.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
INPUT=$ROOT/bench/lammps-pile.in
LMP=${LMP:-lmp}
OUT=${OUT:-$ROOT/out/lammps}
NTRIAL=${NTRIAL:-3}
SCALE=${SCALE:-1}
SIZES=${SIZES:-4 8}
export OMP_NUM_THREADS=1

if ! command -v "$LMP" > /dev/null; then
  echo "LAMMPS not found as '$LMP': apt-get install -y lammps, or set LMP" >&2
  exit 1
fi
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)
CSV=$OUT/throughput_lammps.csv

# Timed steps and repeats per process for each phase; the step counts are
# those of `repose bench` (50 000 / 20 000 for W = 4, 20 000 / 20 000 above).
phases_for() {
  if [ "$1" -le 4 ]; then
    printf '%s\n' "settled 50000 5" "flow 20000 10"
  else
    printf '%s\n' "settled 20000 5" "flow 20000 5"
  fi
}

# From a timed run's log: grains at the start and end, particle-steps (the
# grain count, printed every 100 steps, integrated with the trapezoid rule)
# and LAMMPS's own loop time summed over the repeats.
read_log() {
  awk '
    /^ *Step +Time +Atoms/ { inrun = 1; first = 1; next }
    /^Loop time of/        { inrun = 0; loop += $4; last = $(NF - 1); next }
    inrun && $1 ~ /^[0-9]+$/ {
      if (first) { if (start == "") start = $3 }
      else       { work += 0.5 * (n + $3) * ($1 - s) }
      s = $1; n = $3; first = 0
    }
    END { printf "%d %d %.0f %.6g\n", start, last, work, loop }
  ' "$1"
}

echo "scene,W,H,phase,nsteps,nrep,trial,N_start,N_end,atom_steps,real_s,loop_s,psteps_per_s_real,psteps_per_s_loop" > "$CSV"
for W in $SIZES; do
  dir=$OUT/W$W
  mkdir -p "$dir"
  if [ ! -f "$dir/settled.restart" ]; then
    echo "filling and settling the W = H = $W box (not timed) ..."
    "$LMP" -nocite -screen none -log "$dir/fill.log" -in "$INPUT" \
      -var stage fill -var W "$W" -var H "$W" -var dir "$dir" < /dev/null \
      || { echo "LAMMPS failed, see $dir/fill.log" >&2; exit 1; }
  fi
  while read -r phase full repeat; do
    steps=$(awk -v n="$full" -v f="$SCALE" 'BEGIN { m = int(n * f + 0.5); print (m < 1 ? 1 : m) }')
    for trial in $(seq 1 "$NTRIAL"); do
      log=$dir/$phase-$trial.log
      t0=$EPOCHREALTIME
      "$LMP" -nocite -screen none -log "$log" -in "$INPUT" \
        -var stage "$phase" -var W "$W" -var dir "$dir" \
        -var steps "$steps" -var repeat "$repeat" < /dev/null \
        || { echo "LAMMPS failed, see $log" >&2; exit 1; }
      t1=$EPOCHREALTIME
      read -r n0 n1 work loop < <(read_log "$log")
      awk -v OFS=, -v csv="$CSV" -v W="$W" -v ph="$phase" -v st="$steps" -v rep="$repeat" -v tr="$trial" \
          -v n0="$n0" -v n1="$n1" -v work="$work" -v loop="$loop" -v t0="$t0" -v t1="$t1" 'BEGIN {
        real = t1 - t0
        print "2D_W" W "H" W, W, W, ph, st, rep, tr, n0, n1, work, sprintf("%.3f", real), loop,
              sprintf("%.4g", work / real), sprintf("%.4g", work / loop) >> csv
        printf "W = H = %s  %-7s  trial %s: %d -> %d grains, %d x %d steps, %.2f M particle-steps/s (wall), %.2f M (loop)\n",
               W, ph, tr, n0, n1, rep, st, work / real / 1e6, work / loop / 1e6
      }'
    done
  done < <(phases_for "$W")
done
echo "wrote $CSV"
