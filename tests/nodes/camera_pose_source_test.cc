/// @file camera_pose_source_test.cc
/// @brief pose_source + camera (sim and replay) as processes; a subscriber checks the frames.
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "msgs/codec.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/raw_subscriber.h"
#include "scene/capture.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/runtime/test_util.h"
#include "tests/process_util.h"
#include "tests/test_paths.h"

namespace p2i::nodes {
namespace {

using p2i::testing::Process;
using runtime::testing::ScopedRunDir;

std::string Bin(const std::string& name) { return p2i::testing::BinDir() + "/" + name; }

/// Receives up to `count` decodable RgbdFrames on /rgbd within `timeout`.
std::vector<msgs::RgbdFrame> ReceiveFrames(runtime::RawSubscriber* sub, size_t count,
                                           std::chrono::seconds timeout) {
  std::vector<msgs::RgbdFrame> frames;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (frames.size() < count && std::chrono::steady_clock::now() < deadline) {
    msgs::WireMessage wire;
    msgs::pb::Header header;
    if (!sub->Receive(&wire, &header, std::chrono::milliseconds(200))) continue;
    msgs::RgbdFrame frame;
    std::string error;
    if (msgs::Decode(wire, &frame, &error)) frames.push_back(std::move(frame));
  }
  return frames;
}

TEST_CASE("pose_source drives the sim camera: frames carry the published poses",
          "[integration]") {
  ScopedRunDir run_dir;
  runtime::RawSubscriber rgbd("/rgbd", {});
  runtime::RawSubscriber info("/camera_info", {});
  Process camera({Bin("p2i_camera"), "backend:=sim", "width:=64", "height:=48", "rate:=40",
                  "pose_mode:=topic", "status_period:=0"});
  Process poses({Bin("p2i_pose_source"), "trajectory:=orbit", "rate:=20", "status_period:=0"});
  REQUIRE(camera.pid() > 0);
  REQUIRE(poses.pid() > 0);

  const std::vector<msgs::RgbdFrame> frames = ReceiveFrames(&rgbd, 8, std::chrono::seconds(30));
  REQUIRE(frames.size() == 8);
  const auto orbit = scene::GenerateOrbit(scene::OrbitOptions());
  std::vector<scene::Pose> seen;
  for (const msgs::RgbdFrame& f : frames) {
    CHECK(f.rgb.width == 64);
    CHECK(f.rgb.height == 48);
    CHECK(f.depth.encoding == msgs::pb::DEPTH32F);
    REQUIRE(f.meta.has_pose());
    REQUIRE(f.meta.has_camera_info());
    CHECK(f.meta.camera_info().width() == 64);
    const scene::Pose pose = convert::FromMsg(f.meta.pose());
    // The camera rendered at a pose that pose_source published (a pose of the orbit).
    double best = 1e9;
    for (const scene::StampedPose& p : orbit) {
      best = std::min(best, scene::Pose::TranslationDistance(p.pose, pose) +
                                scene::Pose::RotationDistanceDeg(p.pose, pose) * 1e-3);
    }
    CHECK(best < 1e-6);
    // And the image is the scene at that pose, not a blank.
    const cv::Mat depth = convert::ToMat(f.depth);
    CHECK(cv::countNonZero(depth > 0.0f) > 64 * 48 / 2);
    seen.push_back(pose);
  }
  CHECK(scene::Pose::TranslationDistance(seen.front(), seen.back()) > 1e-3);  // it moves

  // camera_info is latched: a late subscriber gets it.
  msgs::WireMessage wire;
  msgs::pb::Header header;
  REQUIRE(info.Receive(&wire, &header, std::chrono::milliseconds(5000)));
  msgs::pb::CameraInfo ci;
  std::string error;
  REQUIRE(msgs::Decode(wire, &ci, &error));
  CHECK(ci.width() == 64);
  CHECK(ci.height() == 48);

  CHECK(poses.Terminate() == 0);
  CHECK(camera.Terminate() == 0);
}

TEST_CASE("Replay camera plays a capture folder in order with its poses, looping",
          "[integration]") {
  ScopedRunDir run_dir;
  const std::string dir = run_dir.Path() + "/capture";
  const scene::SimScene sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::CameraInfo::Pinhole(48, 36, 40, 40, 23.5, 17.5);
  auto orbit = scene::GenerateOrbit(scene::OrbitOptions());
  orbit.resize(6);
  {
    scene::CaptureWriter writer(dir, cam);
    for (size_t i = 0; i < orbit.size(); ++i) {
      scene::RgbdSample s = sim.Render(orbit[i].pose, cam);
      s.stamp = 0.05 * i;
      writer.Append(s);
    }
  }
  runtime::RawSubscriber rgbd("/rgbd", {});
  Process camera({Bin("p2i_camera"), "backend:=replay", "dataset:=" + dir, "loop:=true",
                  "rate_scale:=2.0", "width:=24", "height:=24", "status_period:=0"});
  const std::vector<msgs::RgbdFrame> frames = ReceiveFrames(&rgbd, 14, std::chrono::seconds(30));
  REQUIRE(frames.size() == 14);
  // Each frame is one of the recorded frames, in recorded order (mod the loop).
  std::vector<size_t> order;
  for (const msgs::RgbdFrame& f : frames) {
    CHECK(f.rgb.width == 24);
    CHECK(f.rgb.height == 24);
    CHECK(f.meta.camera_info().width() == 24);
    REQUIRE(f.meta.has_pose());
    const scene::Pose pose = convert::FromMsg(f.meta.pose());
    size_t match = orbit.size();
    for (size_t i = 0; i < orbit.size(); ++i) {
      if (orbit[i].pose.equals(pose, 1e-6)) match = i;
    }
    REQUIRE(match < orbit.size());
    order.push_back(match);
  }
  for (size_t k = 1; k < order.size(); ++k) {
    CHECK(order[k] == (order[k - 1] + 1) % orbit.size());
  }
  CHECK(camera.Terminate() == 0);
}

TEST_CASE("Camera node start-up errors exit with code 2 and say why", "[integration]") {
  ScopedRunDir run_dir;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{Bin("p2i_camera"), "backend:=gige"},
        std::vector<std::string>{Bin("p2i_camera"), "backend:=replay",
                                 "dataset:=/nonexistent/folder"},
        std::vector<std::string>{Bin("p2i_pose_source"), "trajectory:=/no/such.txt"}}) {
    Process p(args);
    REQUIRE(p.pid() > 0);
    INFO(args[0] << " " << args[1]);
    CHECK(p.Wait() == 2);
  }
}

}  // namespace
}  // namespace p2i::nodes
