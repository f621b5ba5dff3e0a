#!/bin/bash
# Two hosts of the project's own: network namespaces joined by a veth pair (10.231.N.1/.2, only
# inside the namespaces), `p2i launch two_hosts.yaml` in each (camera + pose_source on "robot",
# trainer + synthesizer + slam_sink on "workstation"). Checks that the workstation's sink writes
# views rendered from the robot's poses by a model trained on the robot's frames, that
# `p2i topic list/hz/bw/delay --peer` work against the remote graph, that CURVE-secured runs
# work too, and prints the link's rate, bandwidth and delay. Exit 77 (ctest: skipped) without
# root or `ip netns`. The namespaces are removed on any exit.
set -u
BIN=${P2I_BIN_DIR:?P2I_BIN_DIR (build/bin) is not set}
HERE=$(cd "$(dirname "$0")" && pwd)
if [ "$(id -u)" != 0 ]; then echo "SKIPPED: needs root for ip netns"; exit 77; fi
if ! ip netns list >/dev/null 2>&1; then echo "SKIPPED: ip netns unavailable"; exit 77; fi

N=$(( ($$ % 200) + 20 ))           # 10.231.N.0/24, distinct per run
A=p2i-mh-a-$$; B=p2i-mh-b-$$
AA=10.231.$N.1; BA=10.231.$N.2
WORK=$(mktemp -d /tmp/p2i-netns-XXXXXX)
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill -INT "$p" 2>/dev/null; done
  sleep 1
  for p in "${PIDS[@]}"; do kill -KILL "$p" 2>/dev/null; done
  ip netns pids "$A" 2>/dev/null | xargs -r kill -KILL 2>/dev/null
  ip netns pids "$B" 2>/dev/null | xargs -r kill -KILL 2>/dev/null
  ip netns del "$A" 2>/dev/null; ip netns del "$B" 2>/dev/null
  rm -rf "$WORK"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$WORK"/*.log; do echo "== $f"; tail -n 30 "$f"; done; exit 1; }

ip netns add "$A" && ip netns add "$B" || fail "ip netns add"
ip link add "veth-a-$$" netns "$A" type veth peer name "veth-b-$$" netns "$B" || fail "veth"
ip -n "$A" addr add "$AA/24" dev "veth-a-$$"; ip -n "$B" addr add "$BA/24" dev "veth-b-$$"
ip -n "$A" link set lo up; ip -n "$B" link set lo up
ip -n "$A" link set "veth-a-$$" up; ip -n "$B" link set "veth-b-$$" up
ip -n "$A" route get "$BA" >/dev/null || fail "no route across the veth pair"

ARGS="robot_address:=$AA workstation_address:=$BA out:=$WORK/out"
run_pair() {  # $1 = label; env P2I_CURVE_DIR optional
  mkdir -p "$WORK/runA" "$WORK/runB"
  ip netns exec "$A" env P2I_RUN_DIR="$WORK/runA" "$BIN/p2i" launch "$HERE/two_hosts.yaml" $ARGS \
      --grace-period 3 > "$WORK/$1-robot.log" 2>&1 &
  PIDS+=($!); PA=$!
  ip netns exec "$B" env P2I_RUN_DIR="$WORK/runB" "$BIN/p2i" launch "$HERE/two_hosts.yaml" $ARGS \
      --grace-period 3 > "$WORK/$1-workstation.log" 2>&1 &
  PIDS+=($!); PB=$!
}
in_b() { ip netns exec "$B" env P2I_RUN_DIR="$WORK/runB" "$@"; }
views() { local n; n=$(grep -vc '^#' "$WORK/out/tum/rgb.txt" 2>/dev/null); echo "${n:-0}"; }
wait_views() {  # $1 = how many
  for i in $(seq 1 240); do [ "$(views)" -ge "$1" ] && return 0; sleep 0.5; done; return 1
}
stop_pair() {
  kill -INT "$PA" "$PB"; wait "$PA"; CA=$?; wait "$PB"; CB=$?
  PIDS=()
  [ "$CA" = 0 ] || fail "robot launch exit code $CA"
  [ "$CB" = 0 ] || fail "workstation launch exit code $CB"
}

# --- plain tcp
run_pair plain
PEER="--peer tcp://$AA:7411"
for i in $(seq 1 60); do
  LIST=$(in_b "$BIN/p2i" topic list -t $PEER 2>&1)
  echo "$LIST" | grep -q '^/rgbd ' && echo "$LIST" | grep -q '^/views ' && break; sleep 0.5
done
echo "$LIST"
echo "$LIST" | grep -q '^/rgbd \[RgbdFrame\]' || fail "workstation does not list the robot's /rgbd"
echo "$LIST" | grep -q '^/pose ' || fail "workstation does not list the robot's /pose"
echo "$LIST" | grep -q '^/views ' || fail "workstation does not list its own /views"
in_b "$BIN/p2i" topic list -v $PEER | grep "/rgbd" | grep -q "tcp://$AA:" \
  || fail "the robot's /rgbd is not listed with its tcp endpoint"
wait_views 5 || fail "no views reached the workstation's sink (got $(views))"
echo "views written by the workstation's sink: $(views)"
HZ=$(in_b "$BIN/p2i" topic hz /rgbd $PEER --duration 3) ; echo "$HZ" | tail -2
echo "$HZ" | grep -q "average rate" || fail "p2i topic hz /rgbd across the link measured nothing"
in_b "$BIN/p2i" topic bw /rgbd $PEER --duration 3 | tail -1
in_b "$BIN/p2i" topic delay /rgbd $PEER --duration 3 | tail -1
in_b "$BIN/p2i" topic echo /pose $PEER --once --timeout 5 | grep -q position \
  || fail "p2i topic echo /pose across the link"
stop_pair

# --- the same graph with CURVE on every tcp endpoint (one key directory per host)
"$BIN/p2i" keygen --init "$WORK/keysA" >/dev/null && "$BIN/p2i" keygen --init "$WORK/keysB" >/dev/null \
  || fail "p2i keygen --init"
PUBA=$(awk '/^public/{print $2}' "$WORK/keysA/self.pub"); PUBB=$(awk '/^public/{print $2}' "$WORK/keysB/self.pub")
echo "$PUBB workstation" >> "$WORK/keysA/authorized_keys"; echo "$PUBA robot" >> "$WORK/keysB/authorized_keys"
printf '%s %s\n%s %s\n' "$AA" "$PUBA" "$BA" "$PUBB" > "$WORK/keysA/servers"; cp "$WORK/keysA/servers" "$WORK/keysB/servers"
rm -rf "$WORK/out"
mkdir -p "$WORK/runA" "$WORK/runB"
ip netns exec "$A" env P2I_RUN_DIR="$WORK/runA" P2I_CURVE_DIR="$WORK/keysA" "$BIN/p2i" launch \
    "$HERE/two_hosts.yaml" $ARGS --grace-period 3 > "$WORK/curve-robot.log" 2>&1 &
PIDS+=($!); PA=$!
ip netns exec "$B" env P2I_RUN_DIR="$WORK/runB" P2I_CURVE_DIR="$WORK/keysB" "$BIN/p2i" launch \
    "$HERE/two_hosts.yaml" $ARGS --grace-period 3 > "$WORK/curve-workstation.log" 2>&1 &
PIDS+=($!); PB=$!
wait_views 5 || fail "CURVE: no views reached the workstation's sink (got $(views))"
echo "CURVE: views written by the workstation's sink: $(views)"
in_b env P2I_CURVE_DIR="$WORK/keysB" "$BIN/p2i" topic bw /rgbd $PEER --duration 3 | tail -1
in_b env P2I_CURVE_DIR="$WORK/keysB" "$BIN/p2i" topic delay /rgbd $PEER --duration 3 | tail -1
# Without keys the workstation sees nothing of the robot.
in_b env -u P2I_CURVE_DIR "$BIN/p2i" topic echo /pose $PEER --once --timeout 3 >/dev/null 2>&1 \
  && fail "a plain client read /pose from a CURVE-secured robot"
grep -q "CURVE: refused" "$WORK/curve-robot.log" || fail "the robot did not log the refused plain client"
stop_pair
echo "PASS"
