#!/bin/bash
# Data-parallel training speed (docs/DISTRIBUTED.md): `p2i train` with 1 and 2 Gloo ranks on
# loopback, the same per-rank batch; prints steps/s (rank 0's progress bar) and the measured
# gradient all-reduce time and bytes (rank 0's distributed.rank0.json), writes JSON.
#   bench/dp_bench.sh [OUT.json] [CONFIG.yaml] [STEPS]     (run from the checkout; build/bin)
set -eu
OUT=${1:-}
CONFIG=${2:-model/presets/demo_64.yaml}
STEPS=${3:-60}
BIN=${P2I_BIN_DIR:-build/bin}
WORK=$(mktemp -d /tmp/p2i-dp-bench-XXXXXX)
trap 'rm -rf "$WORK"' EXIT
PORT=$(( 31000 + $$ % 1000 ))
rows=()
for W in 1 2; do
  PIDS=()
  for R in $(seq 0 $((W - 1))); do
    DIST=""
    [ "$W" -gt 1 ] && DIST="--world-size $W --rank $R --master 127.0.0.1:$PORT"
    nice -n 15 "$BIN/p2i" train "$CONFIG" --data procedural --frames 64 --phase 1 \
        --steps "$STEPS" --threads 1 --out "$WORK/w$W" $DIST > "$WORK/w$W.r$R.log" 2>&1 &
    PIDS+=($!)
  done
  for p in "${PIDS[@]}"; do wait "$p"; done
  RATE=$(tr '\r' '\n' < "$WORK/w$W.r0.log" | grep -o '[0-9.]* it/s' | tail -1 | cut -d' ' -f1)
  MS=0; P50=0; SIZES="[]"; PER_STEP=0; CALLS=0
  if [ -f "$WORK/w$W/distributed.rank0.json" ]; then
    read -r MS P50 SIZES PER_STEP CALLS < <(/usr/bin/python3 -c "
import json; j = json.load(open('$WORK/w$W/distributed.rank0.json'))
print(j['allreduce_ms_mean'], j['allreduce_ms_p50'], json.dumps(j.get('allreduce_sizes_bytes', [j['bytes_per_allreduce']])).replace(' ', ''),
      j.get('allreduce_bytes_total', 0) // $STEPS, j['allreduce_calls'])")
  fi
  LOAD=$(cut -d' ' -f1 /proc/loadavg)
  echo "world_size $W: $RATE steps/s (each rank's batch from $CONFIG), $CALLS all-reduces (sizes $SIZES bytes) mean $MS ms p50 $P50 ms, $PER_STEP bytes per step, load $LOAD"
  rows+=("{\"world_size\": $W, \"steps_per_s\": ${RATE:-0}, \"allreduce_calls\": $CALLS, \"allreduce_ms_mean\": $MS, \"allreduce_ms_p50\": $P50, \"allreduce_sizes_bytes\": $SIZES, \"bytes_per_step\": $PER_STEP, \"load1\": $LOAD}")
  PORT=$((PORT + 1))
done
if [ -n "$OUT" ]; then (IFS=,; echo "[${rows[*]}]") > "$OUT"; fi
