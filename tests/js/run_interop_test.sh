#!/usr/bin/env bash
# ctest driver of the npm interop tests (tests/js/CMakeLists.txt):
#   run_interop_test.sh mcap|ws BIN_DIR
# Starts a sim camera (p2i_camera), then
#   mcap: records 2 s with `p2i record -a --foxglove`, reads it with @mcap/core (mcap_read.mjs)
#   ws  : starts p2i_foxglove_bridge and runs 1 and 4 @foxglove/ws-protocol clients (ws_client.mjs)
# Exit 77 (ctest: Skipped) when node or the packages installed by scripts/setup.sh are missing.
# Nothing is downloaded here.
set -euo pipefail
mode=$1
bin=$2
here="$(cd "$(dirname "$0")" && pwd)"
if ! command -v node >/dev/null 2>&1; then
  echo "SKIPPED: node is not installed (the npm interop tests need node >= 18)"; exit 77
fi
if [ ! -d "$here/node_modules/@mcap/core" ] || [ ! -d "$here/node_modules/@foxglove/ws-protocol" ]; then
  echo "SKIPPED: tests/js/node_modules missing: run scripts/setup.sh (it runs npm ci in tests/js)"; exit 77
fi
work="$(mktemp -d /tmp/p2i-js-test-XXXXXX)"
export P2I_RUN_DIR="$work/run"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
"$bin/p2i_camera" backend:=sim pose_mode:=trajectory width:=48 height:=36 rate:=20 \
  status_period:=0.5 2>"$work/camera.log" &
pids+=($!)
case "$mode" in
  mcap)
    "$bin/p2i" record -a --foxglove -o "$work/rec.mcap" --duration 2 --chunk-size 0.1
    "$bin/p2i" info --json "$work/rec.mcap" > "$work/info.json"
    node "$here/mcap_read.mjs" "$work/rec.mcap" "$work/info.json"
    "$bin/p2i" record -a -o "$work/lz4.mcap" --duration 1 --compression lz4
    "$bin/p2i" info --json "$work/lz4.mcap" > "$work/lz4.json"
    node "$here/mcap_read.mjs" "$work/lz4.mcap" "$work/lz4.json"
    ;;
  ws)
    "$bin/p2i_foxglove_bridge" port:=0 port_file:="$work/port" 2>"$work/bridge.log" &
    pids+=($!)
    for _ in $(seq 1 200); do [ -s "$work/port" ] && break; sleep 0.05; done
    [ -s "$work/port" ] || { echo "bridge did not start:"; cat "$work/bridge.log"; exit 1; }
    url="ws://127.0.0.1:$(cat "$work/port")"
    node "$here/ws_client.mjs" "$url" /rgbd 1
    node "$here/ws_client.mjs" "$url" /rgbd 4
    ;;
  *) echo "usage: $0 mcap|ws BIN_DIR"; exit 2 ;;
esac
