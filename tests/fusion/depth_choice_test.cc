/// @file depth_choice_test.cc
/// @brief `blend.depth: auto` (depth_choice.h): the leave-one-out choice between the TSDF's
/// raycast and the keyframes' own depth follows which of them reproduces held-out frames.
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/depth_choice.h"
#include "fusion/fusion_scene.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

const std::vector<double> kXs = {-0.12, -0.06, 0.0, 0.06, 0.12};

// The true surface is fused; the keyframes (colour and depth sources only) measured it 1.5 %
// deeper, as a sensor's bias that nearby frames share: a held-out frame is matched by its
// neighbours' depth, not by the TSDF.
void AddBiasedKeyframes(const PlaneScene& scene, const scene::CameraInfo& cam, FusionScene* fs) {
  for (double x : kXs) {
    const scene::RgbdSample truth = scene.Render(At(x, 0, 0), cam);
    scene::RgbdSample biased = truth;
    const cv::Mat deeper = truth.depth * 1.015;  // a new buffer: biased shares truth's
    biased.depth = deeper;
    fs->Integrate(truth);
    fs->AddFrame(biased, /*integrate=*/false);
  }
}

// Every frame is fused and kept, each with its own zero-mean depth noise (1.5 % of z): the TSDF
// averages the noise away, one keyframe's depth keeps it.
void AddNoisyFrames(const PlaneScene& scene, const scene::CameraInfo& cam, FusionScene* fs) {
  cv::RNG rng(11);
  for (double x : kXs) {
    scene::RgbdSample f = scene.Render(At(x, 0, 0), cam);
    cv::Mat noise(f.depth.size(), CV_32FC1);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.015);
    f.depth = f.depth.mul(1.0f + noise);
    fs->AddFrame(f);
  }
}

FusionSceneOptions Depth(const std::string& source) {
  FusionSceneOptions o;
  o.blend.depth = source;
  return o;
}

TEST_CASE("Depth choice: a bias the keyframes share picks their depth, independent noise the raycast", "[unit]") {
  PlaneScene scene;
  scene.patch_z = 1.5;
  const auto cam = Cam(48, 36, 45);

  FusionScene biased(cam, Depth("auto"));
  AddBiasedKeyframes(scene, cam, &biased);
  CHECK_FALSE(biased.keyframe_depth());  // nothing chosen before Prepare
  biased.Prepare();
  const DepthChoice& b = biased.depth_choice();
  CHECK(b.source == "keyframes");
  CHECK(biased.keyframe_depth());
  CHECK(b.frames == 5);
  CHECK(b.pixels > 5 * 48 * 36 / 2);
  CHECK(b.abs_rel_raycast == Approx(0.015 / 1.015).margin(0.003));
  CHECK(b.abs_rel_keyframes < 0.5 * b.abs_rel_raycast);
  CHECK_THAT(b.Describe(), Catch::Contains("keyframes") && Catch::Contains("5 keyframes"));

  FusionScene noisy(cam, Depth("auto"));
  AddNoisyFrames(scene, cam, &noisy);
  noisy.Prepare();
  const DepthChoice& n = noisy.depth_choice();
  CHECK(n.source == "raycast");
  CHECK_FALSE(noisy.keyframe_depth());
  CHECK(n.frames == 5);
  CHECK(n.abs_rel_raycast < n.abs_rel_keyframes);

  // Held out at a quarter of the frame's width, the choice is the same.
  CHECK(ChooseDepthSource(biased, 16, 12).source == "keyframes");
  CHECK(ChooseDepthSource(noisy, 3, 12).source == "raycast");
  CHECK(ChooseDepthSource(noisy, 3, 12).frames == 3);
}

TEST_CASE("Depth choice: an auto scene renders exactly what the chosen source's scene renders", "[unit]") {
  PlaneScene scene;
  scene.patch_z = 1.5;
  const auto cam = Cam(48, 36, 45);
  FusionScene automatic(cam, Depth("auto")), keyframes(cam, Depth("keyframes")), raycast(cam, Depth("raycast"));
  for (FusionScene* fs : {&automatic, &keyframes, &raycast}) {
    AddBiasedKeyframes(scene, cam, fs);
    fs->Prepare();
  }
  REQUIRE(automatic.depth_choice().source == "keyframes");
  CHECK(keyframes.depth_choice().frames == 0);  // only auto chooses
  const scene::Pose pose = At(0.03, 0.01, 0);
  const cv::Mat a = automatic.RenderCandidates(pose, cam).depth;
  CHECK(cv::norm(a, keyframes.RenderCandidates(pose, cam).depth, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(a, raycast.RenderCandidates(pose, cam).depth, cv::NORM_INF) > 0.01);
  // A request may still ask for either source.
  CandidateRequest r;
  r.keyframe_depth = false;
  CHECK(cv::norm(automatic.RenderCandidates(pose, cam, r).depth, raycast.RenderCandidates(pose, cam).depth,
                 cv::NORM_INF) == 0.0);
}

TEST_CASE("Depth choice: fewer than 3 keyframes keep the raycast, the YAML key and bad arguments", "[unit]") {
  const PlaneScene scene;
  const auto cam = Cam(32, 24, 30);
  FusionScene fs(cam, Depth("auto"));
  for (double x : {0.0, 0.1}) {
    scene::RgbdSample f = scene.Render(At(x, 0, 0), cam);
    fs.Integrate(f);
    f.depth = f.depth * 1.015;
    fs.AddFrame(f, /*integrate=*/false);
  }
  fs.Prepare();
  CHECK(fs.depth_choice().source == "raycast");
  CHECK(fs.depth_choice().frames == 0);
  CHECK_THAT(fs.depth_choice().Describe(), Catch::Contains("fewer than 3"));
  CHECK(BlendOptions::FromYaml(YAML::Load("{depth: raycast}"), "cfg.yaml").depth == "raycast");
  CHECK(BlendOptions::FromYaml(YAML::Load("{}"), "cfg.yaml").depth == "auto");  // the default
  CHECK_THROWS_WITH(ChooseDepthSource(fs, 0, 160), Catch::Contains("max_frames"));
  CHECK_THROWS_WITH(ChooseDepthSource(fs, 4, 4), Catch::Contains("max_width"));
}

}  // namespace
}  // namespace p2i::fusion
