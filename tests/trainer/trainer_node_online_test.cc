/// @file trainer_node_online_test.cc
/// @brief TrainerNode in-process, online: RgbdFrames on "rgbd" reach the buffer (resized,
/// persisted); frames without a pose are counted and dropped.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/shutdown.h"
#include "nodes/trainer/trainer_node.h"
#include "tests/runtime/test_util.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;

namespace {

uint64_t Counter(const runtime::Node& node, const std::string& key) {
  const auto s = node.MakeStatus();
  const auto it = s.counters().find(key);
  return it == s.counters().end() ? 0 : it->second;
}

}  // namespace

TEST_CASE("TrainerNode online: posed frames fill the buffer, pose-less ones are counted",
          "[unit]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir = trainer::testing::TempDir("online");
  const scene::RgbdDataset sim = trainer::testing::SimFrames(6);
  {
    std::ofstream(dir + "/tiny.yaml") << trainer::testing::TinyConfig().ToYamlString();
  }
  runtime::Node camera("cam", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  auto pub = camera.Advertise<msgs::RgbdFrame>("rgbd");
  uint64_t accepted = 0, no_pose = 0;
  {
    trainer::TrainerNode node(runtime::NodeArgs::Parse(std::vector<std::string>{
        "config:=" + dir + "/tiny.yaml", "work_dir:=" + dir + "/work", "max_rounds:=0"}));
    camera.Start();
    node.Start();
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    size_t i = 0;
    while (std::chrono::steady_clock::now() < deadline &&
           (Counter(node, "frames_accepted") < 5 || Counter(node, "frames_without_pose") < 1)) {
      const auto& f = sim.frames[i % sim.frames.size()];
      msgs::RgbdFrame m;
      convert::ToMsg(sim.camera, m.meta.mutable_camera_info());
      if (i % 3 != 2) convert::ToMsg(f.pose, m.meta.mutable_pose());
      m.rgb = convert::ToImage(f.rgb);
      m.depth = convert::ToImage(f.depth);
      pub->Publish(m);
      ++i;
      for (int k = 0; k < 5; ++k) {
        camera.SpinOnce(std::chrono::milliseconds(1));
        node.SpinOnce(std::chrono::milliseconds(2));
      }
    }
    accepted = Counter(node, "frames_accepted");
    no_pose = Counter(node, "frames_without_pose");
    REQUIRE(accepted >= 5);
    REQUIRE(no_pose >= 1);
  }
  // What was accepted is on disk at the training resolution.
  trainer::ReplayBuffer::Options o;
  o.dir = dir + "/work/buffer";
  o.width = o.height = 32;
  trainer::ReplayBuffer reloaded(o);
  CHECK(reloaded.Size() == accepted);
  const auto snap = reloaded.Snapshot();
  REQUIRE_FALSE(snap.frames.empty());
  CHECK(snap.frames[0].rgb.cols == 32);
  CHECK(snap.camera.image_width == 32);
  std::filesystem::remove_all(dir);
}
