#!/bin/bash
# The 3D heap side by side with LIGGGHTS, one process at a time: the peer
# run (../shared/peers/bench_liggghts.sh, `epsd2` rolling friction) and
# `repose bench --heap` alternately, NTRIAL times; prints each trial's
# particle-steps per second and ratio, and the medians.
#
#   apt-get install -y liggghts && cargo build --release
#   NTRIAL=3 scripts/bench-heap.sh
set -euo pipefail
PEERS=${PEERS:-$(cd "$(dirname "$0")/../.." && pwd)/shared/peers}
OUT=${OUTDIR:-$PWD/target/heap-bench}
NTRIAL=${NTRIAL:-3}
REPOSE=${REPOSE:-$PWD/target/release/repose}
mkdir -p "$OUT"
for t in $(seq 1 "$NTRIAL"); do
  OUTDIR="$OUT/liggghts-$t" NTRIAL=1 "$PEERS/bench_liggghts.sh" > "$OUT/liggghts-$t.log"
  "$REPOSE" bench --heap --json > "$OUT/repose-$t.json" 2> /dev/null
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
