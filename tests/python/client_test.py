#!/usr/bin/python3
"""ctest: python/p2i_client.py against real nodes (tests/python/CMakeLists.txt).

Starts p2i_synthesizer (method nearest on the built-in scene) and a sim p2i_camera in a private
$P2I_RUN_DIR, then: renders two poses through the render service and saves them; subscribes to
/rgbd and saves three frames; runs the command line once. Exit 77 (ctest: Skipped) when
Debian's python3-zmq / python3-protobuf or the generated p2i_pb2.py are missing.
    client_test.py BIN_DIR PYTHON_DIR(with p2i_pb2.py) SOURCE_DIR
"""
import os
import subprocess
import sys
import tempfile
import time

bin_dir, py_dir, src_dir = sys.argv[1:4]
try:
    import zmq  # noqa: F401
    import google.protobuf  # noqa: F401
except ImportError as e:
    print("SKIPPED: %s (install python3-zmq python3-protobuf)" % e)
    sys.exit(77)
if not os.path.exists(os.path.join(py_dir, "p2i_pb2.py")):
    print("SKIPPED: %s/p2i_pb2.py not generated (build target p2i_python)" % py_dir)
    sys.exit(77)
os.environ["P2I_PYTHON_DIR"] = py_dir
sys.path.insert(0, os.path.join(src_dir, "python"))
import p2i_client  # noqa: E402

work = tempfile.mkdtemp(prefix="p2i-py-test-")
os.environ["P2I_RUN_DIR"] = os.path.join(work, "run")
procs = []


def start(*args):
    p = subprocess.Popen([os.path.join(bin_dir, args[0])] + list(args[1:]),
                         stderr=open(os.path.join(work, args[0] + ".log"), "w"))
    procs.append(p)
    return p


def check(cond, what):
    if not cond:
        for name in os.listdir(work):
            if name.endswith(".log"):
                print("--- %s\n%s" % (name, open(os.path.join(work, name)).read()[-2000:]))
        raise SystemExit("FAIL: " + what)


try:
    start("p2i_synthesizer", "method:=nearest", "dataset:=builtin:small_office", "width:=32",
          "height:=32", "topic_mode:=false")
    start("p2i_camera", "backend:=sim", "pose_mode:=trajectory", "width:=48", "height:=36",
          "rate:=20")
    client = p2i_client.Client()
    # The synthesizer renders its training data at start-up: retry until it answers.
    views, deadline = None, time.monotonic() + 60
    while views is None and time.monotonic() < deadline:
        try:
            views = client.render([[0.5, 0.0, 1.2, 0, 0, 0, 1], [0.4, 0.1, 1.2, 0, 0, 0.0998, 0.995]],
                                  timeout_s=2.0, retries=0)
        except p2i_client.P2iError as e:
            last = str(e)
            time.sleep(0.5)
    check(views is not None, "no render reply: " + (last if views is None else ""))
    check(len(views) == 2, "2 views")
    for i, (meta, rgb, depth) in enumerate(views):
        check(meta.method == "nearest", "method " + meta.method)
        # The geometry fields are proto3 optionals: absent (not 0) for a method without geometry.
        check(not meta.HasField("observed_fraction"), "nearest sets no observed_fraction")
        check(p2i_client.GeometryText(meta) == "", "no geometry text for nearest")
        meta.observed_fraction = 0.5
        meta.keyframe_angle_deg = 3.0
        check(p2i_client.GeometryText(meta) == ", observed 0.500, keyframe angle 3.0 deg",
              "geometry text: " + p2i_client.GeometryText(meta))
        check(rgb is not None and rgb.width == 32 and rgb.height == 32, "rgb image 32x32")
        path = rgb.save(os.path.join(work, "view%d_rgb" % i))
        check(os.path.getsize(path) == len(b"P6\n32 32\n255\n") + 32 * 32 * 3, "PPM size")
        dpath = depth.save(os.path.join(work, "view%d_depth" % i))
        check(os.path.getsize(dpath) == len(b"P5\n32 32\n65535\n") + 32 * 32 * 2, "PGM size")
        check(max(depth.depth_mm()) > 0, "depth has values")
    # A bad pose is refused by the client before sending.
    try:
        client.render([[0, 0, 0, 0, 0, 0, 2]])
        check(False, "non-unit quaternion accepted")
    except p2i_client.P2iError:
        pass
    frames = list(client.subscribe("/rgbd", count=3, timeout_s=20))
    check(len(frames) == 3, "3 frames")
    seqs = [h.seq for h, _, _ in frames]
    check(seqs == sorted(seqs) and len(set(seqs)) == 3, "increasing seq %s" % seqs)
    head, msg, images = frames[0]
    check(msg.camera_info.width == 48 and len(images) == 2, "frame content")
    check(images[0].save(os.path.join(work, "frame_rgb")).endswith(".ppm"), "frame saved")
    # The command line, as in the README.
    out = subprocess.run(["/usr/bin/python3", os.path.join(src_dir, "python", "p2i_client.py"),
                          "subscribe", "/rgbd", "--count", "2", "--out", os.path.join(work, "cli")],
                         capture_output=True, text=True, timeout=60)
    check(out.returncode == 0, "cli exit %d: %s" % (out.returncode, out.stderr))
    check(out.stdout.count("RGBD_FRAME") == 2, "cli printed 2 frames: " + out.stdout)
    check(len(os.listdir(os.path.join(work, "cli"))) == 4, "cli saved 2 rgb + 2 depth")
    print("ok: 2 views rendered and saved, 3 + 2 frames received")
finally:
    for p in procs:
        p.terminate()
    for p in procs:
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
    subprocess.run(["rm", "-rf", work])
