/// @file live_camera_node_test.cc
/// @brief p2i_camera with live backends as a process: aravis against `arv-fake-gv-camera-0.8`
/// over GigE Vision on 127.0.0.1 with poses matched from a test publisher; libcamera's
/// start-up error.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "convert/image.h"
#include "convert/pose.h"
#include "msgs/codec.h"
#include "nodes/camera/live_backend.h"
#include "nodes/runtime/publisher.h"
#include "nodes/runtime/raw_publisher.h"
#include "nodes/runtime/raw_subscriber.h"
#include "scene/trajectory.h"
#include "tests/process_util.h"
#include "tests/runtime/test_util.h"
#include "tests/skip.h"
#include "tests/test_paths.h"

namespace p2i::nodes {
namespace {

using p2i::testing::Process;
using p2i::testing::RunCommand;
using runtime::testing::ScopedRunDir;

std::string Bin(const std::string& name) { return p2i::testing::BinDir() + "/" + name; }

constexpr const char* kFakeGv = "/usr/bin/arv-fake-gv-camera-0.8";

/// True when something listens on UDP 127.0.0.1:3956 (GVCP), i.e. the fake camera is up.
bool GvcpListening() {
  std::ifstream udp("/proc/net/udp");
  std::string line;
  while (std::getline(udp, line)) {
    if (line.find("0100007F:0F74") != std::string::npos) return true;
  }
  return false;
}

/// The pose the test publishes for a stamp: x = seconds since t0, yaw = 0.2 rad per second.
/// Linear in time, so lerp/SLERP between any two of them is exact.
scene::Pose Truth(int64_t stamp_ns, int64_t t0_ns) {
  const double t = static_cast<double>(stamp_ns - t0_ns) * 1e-9;
  return scene::Pose(Eigen::Vector3d(t, 0.5, 1.0),
                     Eigen::Quaterniond(Eigen::AngleAxisd(0.2 * t, Eigen::Vector3d::UnitZ())));
}

/// The counters of the newest /camera status once `key` exceeds `above` (or at `timeout`).
std::map<std::string, uint64_t> WaitCounter(runtime::RawSubscriber* status, const std::string& key,
                                            uint64_t above, std::chrono::milliseconds timeout) {
  std::map<std::string, uint64_t> out;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    msgs::WireMessage wire;
    msgs::pb::Header header;
    if (!status->Receive(&wire, &header, std::chrono::milliseconds(100))) continue;
    msgs::pb::NodeStatus s;
    std::string error;
    if (!msgs::Decode(wire, &s, &error)) continue;
    out.clear();
    for (const auto& [k, v] : s.counters()) out[k] = v;
    if (out[key] > above) break;
  }
  return out;
}

// long-function: one scenario: one fake camera and node through three pose phases (none,
// streaming, stopped); each phase's counts start from the ones the previous phase left.
TEST_CASE("aravis backend over GigE Vision (arv-fake-gv-camera on 127.0.0.1): frames carry "
          "poses matched by stamp, frames without poses are dropped and counted",
          "[integration]") {
  if (!HaveAravis()) P2I_SKIP("p2i_camera was built without Aravis (libaravis-dev)");
  if (access(kFakeGv, X_OK) != 0) {
    P2I_SKIP(kFakeGv << " not installed (Debian package aravis-tools)");
  }
  if (GvcpListening()) {
    P2I_SKIP("UDP 127.0.0.1:3956 (GVCP) is already in use, another GigE Vision (fake) "
             "camera runs here; only one can listen on the port");
  }
  ScopedRunDir run_dir;
  Process fake({kFakeGv, "-i", "127.0.0.1", "-s", "P2ITEST"});
  REQUIRE(fake.pid() > 0);
  REQUIRE(runtime::testing::WaitUntil(GvcpListening, std::chrono::milliseconds(5000)));

  runtime::RawSubscriber rgbd("/rgbd", {});
  runtime::RawSubscriber status("/camera/status", {});
  Process camera({Bin("p2i_camera"), "backend:=aravis", "device:=Aravis-Fake-P2ITEST",
                  "pixel_format:=RGB8", "width:=64", "height:=48", "frame_rate:=20",
                  "depth_device:=Fake_1", "depth_scale:=0.001", "depth_tolerance:=0.03",
                  "camera_info_file:=" + p2i::testing::SourceDir() + "/calib/aravis_fake.yaml",
                  "pose_tolerance:=0.1", "pose_wait:=0.3", "status_period:=0.2"});
  REQUIRE(camera.pid() > 0);

  // Phase 1: no poses yet. Frames are captured, none published, all counted as dropped.
  std::map<std::string, uint64_t> c =
      WaitCounter(&status, "frames_dropped_no_pose", 0, std::chrono::seconds(10));
  REQUIRE(camera.Running());
  CHECK(c["frames_captured"] > 0);
  CHECK(c["frames_dropped_no_pose"] > 0);
  CHECK(c["frames_published"] == 0);
  msgs::WireMessage wire;
  msgs::pb::Header header;
  CHECK_FALSE(rgbd.Receive(&wire, &header, std::chrono::milliseconds(10)));

  // Phase 2: poses at 50 Hz, stamped now, from this test.
  const int64_t t0 = runtime::NowNs();
  std::atomic<bool> publish{true};
  std::thread poses([&] {
    auto raw = std::make_shared<runtime::RawPublisher>("/pose", "PoseStamped", "/test_poses",
                                                       runtime::PublisherOptions{});
    runtime::Publisher<msgs::pb::PoseStamped> pub(raw, "/test_poses");
    while (publish) {
      msgs::pb::PoseStamped m;
      const int64_t now = runtime::NowNs();
      m.mutable_header()->set_capture_stamp_ns(now);
      m.mutable_header()->set_frame_id("world");
      convert::ToMsg(Truth(now, t0), m.mutable_pose());
      pub.Publish(m);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  std::vector<msgs::RgbdFrame> frames;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (frames.size() < 6 && std::chrono::steady_clock::now() < deadline) {
    if (!rgbd.Receive(&wire, &header, std::chrono::milliseconds(200))) continue;
    msgs::RgbdFrame f;
    std::string error;
    if (msgs::Decode(wire, &f, &error)) frames.push_back(std::move(f));
  }
  publish = false;
  poses.join();
  REQUIRE(frames.size() == 6);
  int with_depth = 0;
  for (const msgs::RgbdFrame& f : frames) {
    CHECK(f.rgb.encoding == msgs::pb::RGB8);
    CHECK(f.rgb.width == 64);
    CHECK(f.rgb.height == 48);
    CHECK(f.depth.encoding == msgs::pb::DEPTH32F);
    REQUIRE(f.meta.has_camera_info());
    CHECK(f.meta.camera_info().width() == 64);
    CHECK(f.meta.camera_info().k(0) == Approx(525.0 * 64 / 640));  // calib scaled to 64x48
    REQUIRE(f.meta.has_pose());
    // The pose is the one at the frame's capture stamp (interpolated between two published).
    const int64_t stamp = f.meta.header().capture_stamp_ns();
    CHECK(stamp > t0);
    const scene::Pose pose = convert::FromMsg(f.meta.pose());
    INFO("stamp - t0 = " << (stamp - t0) * 1e-9 << " s; pose " << pose);
    CHECK(pose.equals(Truth(stamp, t0), 1e-6));
    if (cv::countNonZero(convert::ToMat(f.depth) > 0.0f) > 64 * 48 / 2) ++with_depth;
  }
  CHECK(with_depth >= 4);

  // Phase 3: poses stop; frames are dropped again and counted.
  const uint64_t dropped_before =
      WaitCounter(&status, "", 0, std::chrono::milliseconds(400))["frames_dropped_no_pose"];
  c = WaitCounter(&status, "frames_dropped_no_pose", dropped_before, std::chrono::seconds(5));
  CHECK(c["frames_dropped_no_pose"] > dropped_before);
  CHECK(c["frames_published"] >= 6);
  CHECK(c["frames_dropped_no_pose"] ==
        c["frames_dropped_pose_too_old"] + c["frames_dropped_pose_gap"] +
            c["frames_dropped_pose_timeout"] + c["frames_dropped_pose_overflow"]);

  CHECK(camera.Terminate() == 0);
  fake.Terminate();
}

TEST_CASE("aravis (in-process fake) + p2i_pose_source: every frame's pose lies on the published "
          "trajectory, between two consecutive poses", "[integration]") {
  if (!HaveAravis()) P2I_SKIP("p2i_camera was built without Aravis (libaravis-dev)");
  ScopedRunDir run_dir;
  runtime::RawSubscriber rgbd("/rgbd", {});
  Process camera({Bin("p2i_camera"), "backend:=aravis", "device:=Fake_1", "pixel_format:=Mono8",
                  "width:=32", "height:=24", "frame_rate:=25", "status_period:=0"});
  Process poses({Bin("p2i_pose_source"), "trajectory:=orbit", "rate:=30", "status_period:=0"});
  REQUIRE(camera.pid() > 0);
  REQUIRE(poses.pid() > 0);
  std::vector<scene::Pose> seen;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (seen.size() < 8 && std::chrono::steady_clock::now() < deadline) {
    msgs::WireMessage wire;
    msgs::pb::Header header;
    if (!rgbd.Receive(&wire, &header, std::chrono::milliseconds(200))) continue;
    msgs::RgbdFrame f;
    std::string error;
    if (!msgs::Decode(wire, &f, &error)) continue;
    CHECK(f.rgb.width == 32);
    CHECK(f.depth.encoding == msgs::pb::DEPTH32F);
    CHECK(cv::countNonZero(convert::ToMat(f.depth)) == 0);  // no depth device: all invalid
    REQUIRE(f.meta.has_pose());
    seen.push_back(convert::FromMsg(f.meta.pose()));
  }
  REQUIRE(seen.size() == 8);
  // pose_source publishes the orbit's poses in order (looping); a frame between two of them
  // gets their interpolation: translation on the chord, rotation the SLERP at the same alpha.
  const auto orbit = scene::GenerateOrbit(scene::OrbitOptions());
  int interior = 0;  // strictly between two published poses (not just the newest pose)
  for (const scene::Pose& p : seen) {
    INFO(p);
    bool on_segment = false;
    for (size_t k = 0; k < orbit.size() && !on_segment; ++k) {
      const scene::Pose& a = orbit[k].pose;
      const scene::Pose& b = orbit[(k + 1) % orbit.size()].pose;
      const Eigen::Vector3d ab = b.translation() - a.translation();
      if (ab.squaredNorm() < 1e-12) continue;
      const double alpha = (p.translation() - a.translation()).dot(ab) / ab.squaredNorm();
      if (alpha < -1e-9 || alpha > 1.0 + 1e-9) continue;
      on_segment = scene::Pose::Interpolate(a, b, std::clamp(alpha, 0.0, 1.0)).equals(p, 1e-6);
      if (on_segment && alpha > 0.02 && alpha < 0.98) ++interior;
    }
    CHECK(on_segment);
  }
  CHECK(interior >= 4);  // 25 frames/s against 30 poses/s: most stamps fall between poses
  CHECK(poses.Terminate() == 0);
  CHECK(camera.Terminate() == 0);
}

TEST_CASE("aravis backend: a missing device is a start-up error naming it", "[integration]") {
  if (!HaveAravis()) P2I_SKIP("p2i_camera was built without Aravis (libaravis-dev)");
  ScopedRunDir run_dir;
  int code = 0;
  const std::string out = RunCommand(
      Bin("p2i_camera") + " backend:=aravis device:=No-Such-Camera-42 status_period:=0 2>&1",
      &code);
  CHECK(code == 2);
  CHECK(out.find("No-Such-Camera-42") != std::string::npos);
}

TEST_CASE("libcamera backend exits non-zero naming the problem (not built or no camera)",
          "[integration]") {
  ScopedRunDir run_dir;
  int code = 0;
  const std::string out =
      RunCommand(Bin("p2i_camera") + " backend:=libcamera status_period:=0 2>&1", &code);
  INFO(out);
  CHECK(code == 2);
  CHECK((out.find("built without libcamera") != std::string::npos ||
         out.find("no camera found") != std::string::npos));
}

}  // namespace
}  // namespace p2i::nodes
