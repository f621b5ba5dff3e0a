#!/bin/bash
# Data-parallel training speed (docs/DISTRIBUTED.md): 1 and 2 Gloo ranks on loopback with the
# same per-rank batch, for `p2i train` and for the trainer node (p2i_trainer offline, each rank
# on its shard of the same frames). Every configuration runs REPEATS times; the median is printed.
#   p2i train: steps/s of rank 0's progress bar (training steps only), all-reduce time and bytes
#              from rank 0's distributed.rank0.json.
#   node:      rounds of ROUND_STEPS steps (publish_every_steps), steps/s from the first to the
#              last published version (so each round's set-up, the checkpoint broadcast,
#              validation and the version copy are included), all-reduce figures as above.
# Data: DATA (a dataset folder), else a 64-frame orbit of builtin:small_office rendered at
# 160x120 into the work folder. Every rank runs at nice 15 with --threads 1.
#   bench/dp_bench.sh [OUT.json] [CONFIG.yaml] [STEPS] [REPEATS] [ROUND_STEPS]
#   (run from the checkout; binaries from P2I_BIN_DIR, default build/bin)
set -eu
OUT=${1:-}
CONFIG=${2:-model/presets/demo_64.yaml}
STEPS=${3:-30}
REPEATS=${4:-3}
ROUND_STEPS=${5:-10}
ROUNDS=4  # the node: versions 1..4, timed from version 1 to 4 (3 rounds)
BIN=${P2I_BIN_DIR:-build/bin}
WORK=$(mktemp -d /tmp/p2i-dp-bench-XXXXXX)
trap 'rm -rf "$WORK"' EXIT
PORT=$(( 31000 + $$ % 1000 * 16 % 16000 ))
DATA=${DATA:-}
if [ -z "$DATA" ]; then
  DATA=$WORK/data
  "$BIN/p2i" render builtin:small_office -t orbit --out "$DATA" --width 160 --height 120 \
      --max-frames 64 > "$WORK/render.log" 2>&1 || { cat "$WORK/render.log"; exit 1; }
fi
export P2I_RUN_DIR=$WORK/run  # the node ranks' endpoints, apart from any running graph
mkdir -p "$P2I_RUN_DIR"

# stats DIR RANK_JSON STEPS -> "mean_ms p50_ms sizes bytes_per_step calls" (zeros without file)
stats() {
  if [ -f "$1" ]; then
    /usr/bin/python3 -c "
import json, sys; j = json.load(open('$1'))
print(j['allreduce_ms_mean'], j['allreduce_ms_p50'],
      json.dumps(j.get('allreduce_sizes_bytes', [j['bytes_per_allreduce']])).replace(' ', ''),
      j.get('allreduce_bytes_total', 0) // $2, j['allreduce_calls'])"
  else
    echo "0 0 [] 0 0"
  fi
}

# train_run W DIR: one `p2i train` run with W ranks; prints "steps_per_s mean p50 sizes per_step calls"
train_run() {
  local W=$1 D=$2 PIDS=() R DIST
  for R in $(seq 0 $((W - 1))); do
    DIST=""
    [ "$W" -gt 1 ] && DIST="--world-size $W --rank $R --master 127.0.0.1:$PORT"
    nice -n 15 "$BIN/p2i" train "$CONFIG" --data "$DATA" --phase 1 --steps "$STEPS" --threads 1 \
        --out "$D" $DIST > "$D.r$R.log" 2>&1 &
    PIDS+=($!)
  done
  for p in "${PIDS[@]}"; do wait "$p" || { cat "$D.r0.log" >&2; exit 1; }; done
  local RATE
  RATE=$(tr '\r' '\n' < "$D.r0.log" | grep -o '[0-9.]* it/s' | tail -1 | cut -d' ' -f1)
  echo "${RATE:-0} $(stats "$D/distributed.rank0.json" "$STEPS")"
}

# node_run W DIR: W p2i_trainer ranks offline; prints "steps_per_s mean p50 sizes per_step calls"
node_run() {
  local W=$1 D=$2 PIDS=() R NS
  for R in $(seq 0 $((W - 1))); do
    NS=""
    [ "$R" -gt 0 ] && NS="--namespace /rank$R"
    nice -n 15 "$BIN/p2i_trainer" $NS config:="$CONFIG" dataset:="$DATA" work_dir:="$D/r$R" \
        publish_every_steps:="$ROUND_STEPS" enet_steps_per_version:=0 max_rounds:=$ROUNDS \
        threads:=1 min_frames:=8 world_size:=$W rank:=$R master:=127.0.0.1:$PORT \
        > "$D.r$R.log" 2>&1 &
    PIDS+=($!)
  done
  local LAST
  LAST=$(printf '%s/r0/versions/model_v%06d.pt' "$D" "$ROUNDS")
  local deadline=$((SECONDS + 1800))
  while [ ! -f "$LAST" ] && [ $SECONDS -lt $deadline ]; do
    kill -0 "${PIDS[0]}" 2> /dev/null || { cat "$D.r0.log" >&2; exit 1; }
    sleep 0.5
  done
  sleep 2  # the last round's statistics file
  for p in "${PIDS[@]}"; do kill -TERM "$p" 2> /dev/null || true; done
  for p in "${PIDS[@]}"; do wait "$p" || true; done
  [ -f "$LAST" ] || { echo "node: no version $ROUNDS" >&2; cat "$D.r0.log" >&2; exit 1; }
  local FIRST T0 T1
  FIRST=$(printf '%s/r0/versions/model_v%06d.pt' "$D" 1)
  T0=$(date -r "$FIRST" +%s.%N)
  T1=$(date -r "$LAST" +%s.%N)
  local RATE
  RATE=$(/usr/bin/python3 -c "print(round($(( (ROUNDS - 1) * ROUND_STEPS )) / ($T1 - $T0), 3))")
  echo "$RATE $(stats "$D/r0/distributed.rank0.json" $(( ROUNDS * ROUND_STEPS )))"
}

rows=()
for KIND in train node; do
  for W in 1 2; do
    RUNS=()
    for K in $(seq 1 "$REPEATS"); do
      LOAD=$(cut -d' ' -f1 /proc/loadavg)
      PORT=$((PORT + 1))  # a fresh master port per run (the runs are subshells)
      if [ "$KIND" = train ]; then R=$(train_run "$W" "$WORK/$KIND.w$W.$K"); else R=$(node_run "$W" "$WORK/$KIND.w$W.$K"); fi
      RUNS+=("$R $LOAD")
      echo "  $KIND world_size $W run $K: steps/s $(echo "$R" | cut -d' ' -f1), load before $LOAD" >&2
    done
    ROW=$(printf '%s\n' "${RUNS[@]}" | /usr/bin/python3 -c "
import json, statistics, sys
runs = [l.split() for l in sys.stdin if l.strip()]
med = lambda k: statistics.median(float(r[k]) for r in runs)
print(json.dumps({'kind': '$KIND', 'world_size': $W, 'repeats': len(runs),
                  'steps_per_s_median': med(0), 'steps_per_s_runs': [float(r[0]) for r in runs],
                  'allreduce_ms_mean_median': med(1), 'allreduce_ms_p50_median': med(2),
                  'allreduce_sizes_bytes': json.loads(runs[0][3]), 'bytes_per_step': int(runs[0][4]),
                  'allreduce_calls': int(runs[0][5]), 'load1_before': [float(r[6]) for r in runs]}))")
    echo "$ROW" | /usr/bin/python3 -c "
import json, sys; r = json.load(sys.stdin)
print('%s world_size %d: %.3f steps/s median of %d (%s), all-reduce mean %.1f ms p50 %.1f ms (median), sizes %s bytes, %d bytes/step, load before %s' % (
  r['kind'], r['world_size'], r['steps_per_s_median'], r['repeats'], r['steps_per_s_runs'],
  r['allreduce_ms_mean_median'], r['allreduce_ms_p50_median'], r['allreduce_sizes_bytes'],
  r['bytes_per_step'], r['load1_before']))"
    rows+=("$ROW")
  done
done
if [ -n "$OUT" ]; then (IFS=,; echo "[${rows[*]}]") > "$OUT"; fi
