#!/bin/bash
# A two-node Ray cluster on one machine (each node its own `ray start --block` process with
# --num-cpus CPUS), `slslam bench SPEC --address` on it, then both nodes stopped by their PIDs.
#
#   bash scripts/bench_two_node_cluster.sh SPEC OUT [DATA_DIR] [PORT] [CPUS]
#
# Ray turns token authentication on for `ray start --head`; the second node and the driver use
# the same token (~/.ray/auth_token) with RAY_AUTH_MODE=token.
set -euo pipefail
SPEC=$1
OUT=$2
DATA=${3:-$OUT/inputs}
PORT=${4:-6391}
CPUS=${5:-1}
REPO=$(cd "$(dirname "$0")/.." && pwd)
export RAY_AUTH_MODE=token
LOGS=$(mktemp -d /tmp/slslam-cluster-XXXXXX)
ray start --head --num-cpus "$CPUS" --port "$PORT" --include-dashboard=false \
  --temp-dir "$LOGS/ray" --block > "$LOGS/head.log" 2>&1 &
HEAD=$!
NODE=""
stop() {
  [ -n "$NODE" ] && kill "$NODE" 2>/dev/null && wait "$NODE" || true
  kill "$HEAD" 2>/dev/null && wait "$HEAD" || true
}
trap stop EXIT
wait_for() {  # a log line, for up to 120 s
  for _ in $(seq 120); do grep -q "$2" "$1" && return 0; sleep 1; done
  echo "timed out waiting for '$2' in $1" >&2
  return 1
}
wait_for "$LOGS/head.log" "Ray runtime started"
ray start --address "127.0.0.1:$PORT" --num-cpus "$CPUS" --block > "$LOGS/node.log" 2>&1 &
NODE=$!
wait_for "$LOGS/node.log" "Ray runtime started"
for _ in $(seq 60); do  # the second node registered with the head
  [ "$(ray status --address "127.0.0.1:$PORT" 2>/dev/null | grep -c ' node_')" -ge 2 ] && break
  sleep 1
done
ray status --address "127.0.0.1:$PORT" | grep -E " node_|CPU"
cd "$REPO"
/usr/bin/time -f "wall %e s" slslam bench "$SPEC" --out "$OUT" --data-dir "$DATA" \
  --address "127.0.0.1:$PORT" --no-progress
