#!/bin/bash
# The 3D heap side by side with LIGGGHTS, one process at a time: the peer
# run (bench/liggghts-heap.sh, `epsd2` rolling friction) and
# `repose bench --heap` alternately, NTRIAL times; prints each trial's
# particle-steps per second and ratio, and the medians.
#
#   apt-get install -y liggghts && cargo build --release -p repose-cli
#   NTRIAL=3 bench/bench-heap.sh
#   NTRIAL=1 SCALE=0.05 bench/bench-heap.sh   # quick check, shortened runs
#
# Environment: OUT (default out/heap in the repository), REPOSE (default
# target/release/repose), SCALE (factor on both programs' step counts),
# LIGGGHTS (passed on to bench/liggghts-heap.sh).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${OUT:-$ROOT/out/heap}
NTRIAL=${NTRIAL:-3}
SCALE=${SCALE:-1}
REPOSE=${REPOSE:-$ROOT/target/release/repose}
if [ ! -x "$REPOSE" ]; then
  echo "no repose program at $REPOSE: cargo build --release -p repose-cli, or set REPOSE" >&2
  exit 1
fi
mkdir -p "$OUT"
for t in $(seq 1 "$NTRIAL"); do
  OUT="$OUT/liggghts-$t" NTRIAL=1 ROLLING=epsd2 SCALE="$SCALE" \
    "$ROOT/bench/liggghts-heap.sh" > "$OUT/liggghts-$t.log"
  "$REPOSE" bench --heap --scale "$SCALE" --json > "$OUT/repose-$t.json" 2> /dev/null
done
python3 - "$OUT" "$NTRIAL" <<'PY'
import csv, json, statistics, sys
out, n = sys.argv[1], int(sys.argv[2])
ratios = {"pour": [], "settled": []}
print(f"{'trial':<6} {'phase':<8} {'LIGGGHTS M/s':>13} {'repose M/s':>11} {'ratio':>7}")
for t in range(1, n + 1):
    peer = {r["phase"]: float(r["psteps_per_s_loop"])
            for r in csv.DictReader(open(f"{out}/liggghts-{t}/throughput_liggghts.csv"))
            if r["rolling"] == "epsd2"}
    ours = {p["phase"]: p["particle_steps_per_second"] for p in json.load(open(f"{out}/repose-{t}.json"))}
    for phase in ("pour", "settled"):
        ratio = ours[phase] / peer[phase]
        ratios[phase].append((peer[phase], ours[phase], ratio))
        print(f"{t:<6} {phase:<8} {peer[phase] / 1e6:>13.2f} {ours[phase] / 1e6:>11.2f} {ratio:>6.2f}×")
for phase, rows in ratios.items():
    med = lambda k: statistics.median(r[k] for r in rows)
    print(f"median {phase:<8} {med(0) / 1e6:>13.2f} {med(1) / 1e6:>11.2f} {med(2):>6.2f}×")
PY
