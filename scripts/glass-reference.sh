#!/bin/bash
# The glass-stiff reference heaps (Y = 63 GPa): runs every sweep in
# sweeps/glass/ through the service on an SQLite store and writes each
# sweep's samples to data/glass/<sweep>.csv.
#
#   cargo build --release && scripts/glass-reference.sh [SWEEP.toml ...]
#
# A heap of glass costs 10¹⁰–10¹¹ particle-steps (minutes to hours on one
# core), so the runs go through the queue: samples checkpoint every few
# minutes, and running the script again after an interruption continues
# the sweeps already queued in the store (data/glass/glass.db) from their
# checkpoints instead of queueing them anew. While a sweep in it is
# unfinished the store is kept in the repository (a copy made by `repose
# backup` after the server has stopped), so a heap longer than one sitting
# goes on from its last checkpoint on the next machine.
#
# Environment: REPOSE (the program), PORT (8093), STORE (the SQLite store),
# SERVE_LOG (the server's log, data/glass/serve.log), WORKERS (1). Two sets
# of sweeps run side by side on two stores, ports and logs.
set -euo pipefail
cd "$(dirname "$0")/.."
REPOSE=${REPOSE:-$PWD/target/release/repose}
PORT=${PORT:-8093}
SERVER=http://127.0.0.1:$PORT
STORE=${STORE:-$PWD/data/glass/glass.db}
mkdir -p data/glass
if [ $# -eq 0 ]; then set -- sweeps/glass/*.toml; fi

"$REPOSE" serve --database "sqlite://$STORE" --listen "127.0.0.1:$PORT" \
  --checkpoint-every 300 --workers "${WORKERS:-1}" > "${SERVE_LOG:-data/glass/serve.log}" 2>&1 &
SERVE=$!
trap 'kill $SERVE 2>/dev/null; wait $SERVE 2>/dev/null || true' EXIT
for _ in $(seq 1 50); do
  "$REPOSE" status --server "$SERVER" > /dev/null 2>&1 && break
  sleep 0.2
done

# The id of the sweep named in a spec file, queueing it if the store has none.
sweep_id() {
  local name
  name=$(sed -n 's/^name = "\(.*\)"$/\1/p' "$1")
  local id
  id=$("$REPOSE" status --server "$SERVER" | awk -v n="$name" 'index($0, n) { print $1; exit }')
  if [ -z "$id" ]; then
    id=$("$REPOSE" submit "$1" --server "$SERVER" | sed -n 's/^sweep \([0-9a-f-]*\):.*/\1/p')
  fi
  echo "$id"
}

declare -A ids
for spec in "$@"; do ids[$spec]=$(sweep_id "$spec"); done
# A sweep's jobs queued, running and failed, in one line.
counts() {
  "$REPOSE" status --server "$SERVER" | awk -v id="$1" '$1 == id { print $3, $4, $6 }'
}

for spec in "$@"; do
  id=${ids[$spec]}
  echo "waiting for $(basename "$spec") ($id)"
  # (no line while the server does not answer: wait on). An interrupted
  # job that saved a checkpoint since its claim keeps its attempts and
  # goes on from the checkpoint; a failed job is reported, and `repose
  # retry` queues it again.
  while :; do
    if read -r queued running failed < <(counts "$id") &&
      [ "$queued" = 0 ] && [ "$running" = 0 ]; then
      break
    fi
    sleep 30
  done
  [ "$failed" = 0 ] || echo "$(basename "$spec"): $failed jobs failed (repose status $id)" >&2
  out=data/glass/$(basename "$spec" .toml).csv
  "$REPOSE" export "$id" --what samples --server "$SERVER" -o "$out"
  echo "wrote $out"
done
