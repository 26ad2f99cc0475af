#!/bin/bash
# Pours the second paper's heap without cohesion in LIGGGHTS 3.8
# (bench/liggghts-dry-heap.in) and reads each heap with `repose
# measure-heap`, the heap protocol's own reading, so that its angle stands
# beside repose's on the same plate, grains and step (docs/model-3d.md,
# "The dry level in LIGGGHTS"). One process and one core a heap.
#
#   apt-get install -y liggghts
#   cargo build --release -p repose-cli
#   bench/liggghts-dry-heap.sh                      # 1 mm glass, 20 d plate, seeds 0-3
#   SEEDS="0" Y=6.3e9 bench/liggghts-dry-heap.sh    # one softened heap
#
# Environment: LIGGGHTS (default `liggghts`), REPOSE (default
# target/release/repose), OUT (default out/liggghts-dry), SEEDS (default
# "0 1 2 3"), D (grain diameter, m, default 1e-3), Y (Young's modulus, Pa,
# default 6.3e10), G (gravity, m/s^2, default 9.81), PLATE (d, default 20),
# GRAINS (poured, default 1500). Appends a row per heap to OUT/heaps.csv.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
LIGGGHTS=${LIGGGHTS:-liggghts}
REPOSE=${REPOSE:-$ROOT/target/release/repose}
OUT=${OUT:-$ROOT/out/liggghts-dry}
SEEDS=${SEEDS:-0 1 2 3}
D=${D:-1e-3}
Y=${Y:-6.3e10}
G=${G:-9.81}
PLATE=${PLATE:-20}
GRAINS=${GRAINS:-1500}
export OMP_NUM_THREADS=1

for tool in "$LIGGGHTS" "$REPOSE"; do
  command -v "$tool" > /dev/null || {
    echo "$tool not found (apt-get install -y liggghts; cargo build --release -p repose-cli)" >&2
    exit 1
  }
done

# Distinct primes above 10000 for the insertions of one heap (LIGGGHTS
# seeds its insertion with a prime), a block of them per seed.
primes() {
  awk -v from=$((10007 + 5000 * $1)) -v n=200 'BEGIN {
    for (k = from; c < n; k++) {
      p = 1
      for (q = 2; q * q <= k; q++) if (k % q == 0) { p = 0; break }
      if (p) { printf "%s%d", (c ? " " : ""), k; c++ }
    }
  }'
}

mkdir -p "$OUT"
CSV=$OUT/heaps.csv
METRICS="theta_r theta_r_sd theta_r_footprint theta_r_silhouette heap_grains heap_height surface_roughness edge_height"
[ -s "$CSV" ] || echo "seed,d,youngs_modulus,gravity,plate,grains_poured,steps,wall_time,${METRICS// /,}" > "$CSV"
for seed in $SEEDS; do
  dir=$OUT/seed-$seed-Y-$Y-d-$D-g-$G-plate-$PLATE-$GRAINS
  mkdir -p "$dir"
  # A heap poured before (its summary written last) is read again, not poured again.
  if [ ! -s "$dir/summary.txt" ]; then
    start=$(date +%s.%N)
    "$LIGGGHTS" -in "$ROOT/bench/liggghts-dry-heap.in" -log "$dir/log.lammps" \
      -var d "$D" -var Y "$Y" -var g "$G" -var plate "$PLATE" -var grains "$GRAINS" \
      -var dir "$dir" -var seeds $(primes "$seed") < /dev/null > "$dir/screen.txt" 2>&1 \
      || { echo "LIGGGHTS failed, see $dir/screen.txt" >&2; exit 1; }
    awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f\n", b - a }' > "$dir/wall.txt"
  fi
  wall=$(cat "$dir/wall.txt")
  read -r poured steps < <(awk '{ print $2, $6 }' "$dir/summary.txt")
  "$REPOSE" measure-heap "$dir/final.dump" --diameter "$D" --plate "$PLATE" > "$dir/metrics.txt"
  row=$(for m in $METRICS; do awk -v m="$m" '$1 == m { print $2 }' "$dir/metrics.txt"; done | paste -sd,)
  echo "$seed,$D,$Y,$G,$PLATE,$poured,$steps,$wall,$row" >> "$CSV"
  echo "seed $seed: $(grep '^theta_r ' "$dir/metrics.txt"), $(grep '^theta_r_silhouette' "$dir/metrics.txt") ($wall s)"
done
