/// @file method_loader_test.cc
/// @brief Training data specs and the method factory of the synthesizer node.
#include <stdexcept>

#include <catch2/catch.hpp>

#include "fusion/fusion_version_io.h"
#include "nodes/synthesizer/method_loader.h"
#include "scene/capture.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/temp_dir.h"

namespace p2i::nodes {
namespace {

TEST_CASE("Built-in training data and the nearest/warp loaders", "[unit]") {
  const auto sweep = scene::GenerateArmSweep({});
  const int stride = 10;
  const scene::RgbdDataset poses_only =
      LoadTrainingData("builtin:small_office", 32, 24, /*with_frames=*/false, stride);
  REQUIRE(poses_only.frames.size() == (sweep.size() + stride - 1) / stride);
  CHECK(poses_only.camera.image_width == 32);
  CHECK(poses_only.camera.image_height == 24);
  CHECK(poses_only.frames[1].rgb.empty());
  CHECK(scene::Pose::TranslationDistance(poses_only.frames[1].pose, sweep[stride].pose) < 1e-12);

  auto training = std::make_shared<const scene::RgbdDataset>(
      LoadTrainingData("builtin:small_office", 32, 24, /*with_frames=*/true, stride));
  REQUIRE(training->frames.size() == poses_only.frames.size());
  REQUIRE(training->frames[0].rgb.cols == 32);
  REQUIRE(training->frames[0].depth.rows == 24);

  auto nearest = MakeLoader("nearest", {}, training)({0, "", "nearest"});
  const scene::RgbdSample n = nearest->Render(training->frames[3].pose);
  CHECK(cv::norm(n.rgb, training->frames[3].rgb, cv::NORM_L1) == 0.0);  // the keyframe itself

  auto warp = MakeLoader("warp", {}, training)({0, "", "warp"});
  const scene::RgbdSample w = warp->Render(training->frames[3].pose);
  CHECK(w.rgb.cols == 32);
  CHECK(w.depth.rows == 24);
  CHECK(cv::countNonZero(w.depth > 0.0f) > 32 * 24 / 2);

  CHECK_THROWS_AS(MakeLoader("gan", {}, training), std::invalid_argument);
  // The method's own options: read and checked at start-up, bad keys named.
  LoaderOptions opts;
  opts.method_options = "{k: 1, fill_holes: false}";
  CHECK(MakeLoader("warp", opts, training)({0, "", "warp"})->Render(training->frames[3].pose)
            .rgb.cols == 32);
  opts.method_options = "{kk: 1}";
  CHECK_THROWS_WITH(MakeLoader("warp", opts, training), Catch::Contains("kk"));
  opts.method_options = "{k: [";
  CHECK_THROWS_AS(MakeLoader("warp", opts, training), std::invalid_argument);
  auto no_frames = std::make_shared<const scene::RgbdDataset>(poses_only);
  CHECK_THROWS_AS(MakeLoader("warp", {}, no_frames), std::invalid_argument);
  CHECK_THROWS_AS(MakeLoader("nearest", {}, nullptr), std::invalid_argument);
  // Learned methods need a checkpoint path in the spec.
  CHECK_THROWS(MakeLoader("p2i", {}, nullptr)({1, "", "p2i"}));
  CHECK_THROWS(MakeLoader("cnn", {}, nullptr)({1, "/nonexistent/ckpt.pt", "cnn"}));
  CHECK(LoadTrainingData("", 32, 24, true).frames.empty());
  CHECK_THROWS(LoadTrainingData("/nonexistent/dataset", 32, 24, true));
}


TEST_CASE("fusion without training frames waits for versions and loads them at its size",
          "[unit]") {
  // What the trainer node with method fusion publishes: a TSDF snapshot and keyframes.
  const p2i::testing::TempDir dir("loader_fusion_version");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(64, 48);
  const auto sweep = scene::GenerateArmSweep({});
  fusion::FusionScene fused(cam);
  scene::CaptureWriter keyframes(dir.path() + "/keyframes", cam);
  for (size_t i = 0; i < sweep.size(); i += 10) {
    const scene::RgbdSample s = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
    fused.AddFrame(s);
    keyframes.Append(s);
  }
  fusion::FusionVersionInfo info;
  info.version = 1;
  info.keyframes_dir = keyframes.folder();
  info.keyframe_count = keyframes.size();
  const std::string version = fusion::WriteSceneVersion(dir.path() + "/versions", fused, info);

  LoaderOptions options;
  options.width = 32;
  options.height = 32;
  const auto empty = std::make_shared<const scene::RgbdDataset>();
  SynthesizerLoader loader;
  REQUIRE_NOTHROW(loader = MakeLoader("fusion", options, empty));
  const auto synth = loader({1, version, "fusion"});
  CHECK(synth->Name() == "fusion");
  CHECK(synth->Camera().image_width == 32);
  const scene::RgbdSample v = synth->Render(sweep[20].pose);
  CHECK(v.rgb.size() == cv::Size(32, 32));
  CHECK(cv::countNonZero(v.depth > 0.0f) > 32 * 32 * 9 / 10);
  CHECK_THROWS_WITH(loader({2, dir.path(), "fusion"}), Catch::Contains("manifest.json"));
  // A P2I-NET trainer's versions on the same topic are not this synthesizer's.
  CHECK(VersionIsFor("fusion", "fusion"));
  CHECK(VersionIsFor("", "fusion"));
  CHECK_FALSE(VersionIsFor("p2i_net", "fusion"));
  CHECK(VersionIsFor("p2i_net", "p2i"));
  CHECK_FALSE(VersionIsFor("fusion", "p2i"));
  CHECK_FALSE(VersionIsFor("bogus", "p2i"));
  // Methods that cannot load versions still need frames.
  CHECK_THROWS_WITH(MakeLoader("warp", options, empty), Catch::Contains("needs training frames"));
}

}  // namespace
}  // namespace p2i::nodes
