#!/usr/bin/python3
"""Figures for issue 15 items 2 and 3 (docs/RUNTIME.md "Subscription floods", "Launcher death").

flood:  a real XSUB peer against p2i_pose_source's /pose publisher (rate 50 Hz):
        (a) one 1 MB subscription frame, (b) 2000 random subscriptions then one of 8 MB.
        Prints the node's RSS before/after and the longest gap between /pose messages seen by
        a normal subscriber during the flood.
death:  `p2i launch` of pose_source + slam_sink, `kill -9` of the launcher: seconds until both
        children are gone, whether slam_sink wrote summary.json, what the dead launch left in
        /tmp, and whether the next launch removes it.

    /usr/bin/python3 bench/hardening_bench.py [flood|death|all] [--bin build/bin] [--json OUT]

Run under `flock /work/heavy.lock nice -n 15` on a shared box; the load (`uptime`) is printed.
Needs python3-zmq (Debian).
"""
import argparse
import glob
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import zmq


def rss_mib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return -1.0


def registry_endpoint(run_dir, name, limit_s=20.0):
    end = time.time() + limit_s
    while time.time() < end:
        for p in glob.glob(os.path.join(run_dir, "registry", "*.topic.*")):
            try:
                fields = dict(l.split(" ", 1) for l in open(p).read().splitlines() if " " in l)
            except OSError:
                continue
            if fields.get("name") == name:
                return fields["endpoint"]
        time.sleep(0.05)
    raise RuntimeError(f"no publisher of {name} in {run_dir}")


def max_gap(sub, seconds):
    """Receives for `seconds`; returns (messages, longest gap in s between two)."""
    n, last, gap = 0, time.time(), 0.0
    end = time.time() + seconds
    while time.time() < end:
        if sub.poll(20):
            while True:
                try:
                    sub.recv_multipart(zmq.NOBLOCK)
                except zmq.Again:
                    break
                now = time.time()
                gap = max(gap, now - last)
                last = now
                n += 1
    return n, max(gap, time.time() - last)


PEER = r"""
import random, sys, time, zmq
endpoint, case = sys.argv[1], sys.argv[2]
xsub = zmq.Context().socket(zmq.XSUB)
xsub.setsockopt(zmq.SNDHWM, 0)
xsub.connect(endpoint)
time.sleep(0.2)
rng = random.Random(11)
if case == "1MB":
    xsub.send(b"\x01" + b"a" * (1 << 20))
else:
    for _ in range(2000):
        xsub.send(b"\x01" + bytes(rng.getrandbits(8) for _ in range(1 + rng.randrange(16))))
    xsub.send(b"\x01" + b"b" * (8 << 20))
print("sent", flush=True)
time.sleep(3600)
"""


def flood_case(bin_dir, case):
    run_dir = tempfile.mkdtemp(prefix="p2i-flood-bench-")
    env = dict(os.environ, P2I_RUN_DIR=run_dir)
    node = subprocess.Popen([os.path.join(bin_dir, "p2i_pose_source"), "rate:=50",
                             "status_period:=0"], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    ctx = zmq.Context()
    try:
        endpoint = registry_endpoint(run_dir, "/pose")
        sub = ctx.socket(zmq.SUB)
        sub.setsockopt(zmq.SUBSCRIBE, b"/pose\0")
        sub.connect(endpoint)
        max_gap(sub, 1.0)  # warm up
        before = rss_mib(node.pid)
        # The flooding peer is its own process, killed at the end: libzmq's XSUB keeps a copy of
        # what it sent in a trie whose (recursive) destructor overflows the stack for a 1 MB filter.
        peer = subprocess.Popen([sys.executable, "-c", PEER, endpoint, case],
                                stdout=subprocess.PIPE)
        peer.stdout.readline()  # "sent"
        n, gap = max_gap(sub, 3.0)
        peak = rss_mib(node.pid)
        peer.kill()
        peer.wait()
        n2, _ = max_gap(sub, 1.0)
        after = rss_mib(node.pid)
        return {"case": case, "rss_before_mib": round(before, 1), "rss_flood_mib": round(peak, 1),
                "rss_after_peer_left_mib": round(after, 1), "pose_msgs_3s": n,
                "pose_max_gap_s": round(gap, 3), "pose_msgs_after_1s": n2,
                "node_alive": node.poll() is None}
    finally:
        node.send_signal(signal.SIGINT)
        try:
            node.wait(5)
        except subprocess.TimeoutExpired:
            node.kill()
        ctx.destroy(0)
        shutil.rmtree(run_dir, ignore_errors=True)


def death_case(bin_dir):
    work = tempfile.mkdtemp(prefix="p2i-death-bench-")
    out = os.path.join(work, "sink")
    launch = os.path.join(work, "graph.yaml")
    with open(launch, "w") as f:
        f.write("launch:\n"
                "- node: {exec: pose_source, name: poses, param: [{name: rate, value: 50.0}]}\n"
                "- node:\n    exec: slam_sink\n    name: sink\n    param:\n"
                f"    - {{name: out_dir, value: \"{out}\"}}\n"
                "    - {name: summary_period, value: 0.0}\n"
                "    - {name: check, value: false}\n")
    env = {k: v for k, v in os.environ.items() if k != "P2I_RUN_DIR"}
    env["PATH"] = os.path.abspath(bin_dir) + ":" + env.get("PATH", "")
    log = open(os.path.join(work, "launch.log"), "w")
    params_before = set(glob.glob("/tmp/p2i-launch-params-*"))
    launcher = subprocess.Popen([os.path.join(bin_dir, "p2i"), "launch", launch], env=env,
                                stdout=log, stderr=subprocess.STDOUT)
    # The children: processes whose parent is the launcher.
    children = []
    end = time.time() + 30
    while time.time() < end and len(children) < 2:
        time.sleep(0.1)
        children = [int(p) for p in os.listdir("/proc") if p.isdigit() and
                    _ppid(int(p)) == launcher.pid]
    time.sleep(1.5)  # both running and logging
    run_dirs = [d for d in glob.glob(f"/tmp/p2i-{os.getuid()}/launch-{launcher.pid}*")]
    params = sorted(set(glob.glob("/tmp/p2i-launch-params-*")) - params_before)
    t0 = time.time()
    os.kill(launcher.pid, signal.SIGKILL)
    launcher.wait()
    alive = set(children)
    while alive and time.time() - t0 < 20:
        alive = {p for p in alive if os.path.exists(f"/proc/{p}") and _state(p) != "Z"}
        time.sleep(0.005)
    gone_s = time.time() - t0
    time.sleep(0.2)
    left_run = [d for d in run_dirs if os.path.exists(d)]
    left_params = [d for d in params if os.path.exists(d)]
    # The next launch (a short one) should remove what the dead one left.
    nxt = subprocess.run([os.path.join(bin_dir, "p2i"), "launch", launch], env=env, timeout=30,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         preexec_fn=lambda: signal.alarm(3))
    result = {"children": len(children), "children_gone_s": round(gone_s, 3),
              "still_alive_after_20s": len(alive),
              "summary_json": os.path.exists(os.path.join(out, "summary.json")),
              "left_run_dirs": len(left_run), "left_param_dirs": len(left_params),
              "left_after_next_launch": sum(os.path.exists(d) for d in left_run + left_params)}
    for d in left_run + left_params + [work]:  # what neither launch removed
        shutil.rmtree(d, ignore_errors=True)
    return result


def _ppid(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return int(f.read().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return -1


def _state(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return "X"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", nargs="?", default="all", choices=["flood", "death", "all"])
    ap.add_argument("--bin", default="build/bin")
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    rows = {"bin": os.path.abspath(a.bin),
            "uptime": subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()}
    if a.what in ("flood", "all"):
        rows["flood"] = [flood_case(a.bin, "1MB"), flood_case(a.bin, "2000+8MB")]
    if a.what in ("death", "all"):
        rows["death"] = death_case(a.bin)
    print(json.dumps(rows, indent=1))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
