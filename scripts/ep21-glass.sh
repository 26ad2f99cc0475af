#!/bin/bash
# The second paper's reproduction, docs/reproduction-ep21.md: heaps and
# columns at glass's own modulus (63 GPa), since no softening has yet been
# shown to hold a cohesive heap's angle at every gravity level of the
# study (docs/model-3d.md), in the contact form whose
# glass-stiff heaps fit eq. 1, the default (sliding and rolling limits on
# the net normal force, the attraction fading with the overlap; named
# below so that the run keeps its samples whatever the default). `paper`
# and `standard` set the same numerics on these scenes. About 40
# core-hours, so it runs on a store that outlives one run:
#
#   cargo build --release && scripts/ep21-glass.sh
#
# SIGTERM or Ctrl-C saves the running samples and hands them back to the
# store; running the script again goes on from there. The cheap sweeps
# (dry heaps, packed columns) run first and each sweep's samples cheapest
# first (large grains, strong gravity), ahead of any sweep an earlier run
# left queued, so that a run stopped early has finished the most points.
# The store is kept in the repository (a copy made by `repose backup`
# after the run stopped): an unfinished run goes on from its last
# checkpoints on the next machine, and a finished one writes the report
# again in seconds, running nothing. `scripts/ep21-glass.sh --interim`
# writes the report from the samples finished so far, running none, with
# an estimate of what is left.
#
# Environment: REPOSE (the program), STORE (the SQLite store); further
# arguments go to `repose reproduce` (e.g. --workers 1, or --first
# 'gravity=[0,0,-9.81]' to finish Earth's points, figure 2's, first).
# Once fewer samples are left than workers, the running ones take the
# idle workers' cores as extra threads, with the same numbers; a sample's
# thread count is no part of its identity, so `--set numerics.threads=2`
# keeps every finished sample too, and the report names no variant for it.
set -euo pipefail
cd "$(dirname "$0")/.."
REPOSE=${REPOSE:-$PWD/target/release/repose}
STORE=${STORE:-$PWD/data/ep21/glass-net-fading.db}
mkdir -p "$(dirname "$STORE")"
exec "$REPOSE" reproduce --paper ep21 --preset paper \
  --set material.limit_load=net --set material.contact_attraction=fading \
  --database "sqlite://$STORE" --out docs/reproduction-ep21.md \
  --checkpoint-every 300 --raise-priority 1 --order cheapest -q "$@"
