/// @file submap_choice_test.cc
/// @brief Per-capture submaps (`submaps: {frames: capture}`) and `submaps: {use: auto}`
/// (submap_choice.h): one capture keeps no submap; at the first pose jump the global TSDF so far
/// becomes the first capture's submap; the leave-one-out choice uses the submaps where two
/// captures' poses disagree and keeps the global TSDF where they agree.
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/submap_choice.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

FusionSceneOptions PerCapture(const std::string& use) {
  FusionSceneOptions o;
  o.submaps.frames = SubmapOptions::kCapture;
  o.submaps.break_m = 0.3;
  o.submaps.use = use;
  o.blend.depth = "raycast";
  o.blend.align.iterations = 0;
  o.blend.align.automatic = false;
  return o;
}

// Two captures of the plane 1 m away, seven keyframes each along x, 0.15 m apart (parallax: a
// surface a few cm off moves a slot's colours by about a pixel). The second capture, 0.3 m
// beside the first, has recorded poses `offset_m` deeper than where its frames were taken (its
// odometry disagrees with the first's), so its surface lies `offset_m` behind the first's in the
// world and one global TSDF averages the two.
void AddTwoCaptures(const PlaneScene& scene, const scene::CameraInfo& cam, double offset_m, FusionScene* fs) {
  for (int capture = 0; capture < 2; ++capture) {
    for (int i = 0; i < 7; ++i) {
      const double x = -0.45 + 0.15 * i;
      const double y = capture == 0 ? 0.0 : 0.3;
      scene::RgbdSample f = scene.Render(At(x, y, 0), cam);
      if (capture == 1) f.pose = At(x, y, offset_m);
      fs->AddFrame(f);
    }
  }
}

TEST_CASE("Per-capture submaps: one capture keeps none, a pose jump makes the global TSDF so far the first",
          "[unit]") {
  PlaneScene plane;
  plane.patch_z = 1.5;
  const auto cam = Cam(40, 30, 35);
  FusionScene scene(cam, PerCapture("always"));
  TsdfVolume first(scene.options().tsdf);  // the first capture alone
  for (double x : {0.0, 0.05, 0.1, 0.15}) {
    const scene::RgbdSample f = plane.Render(At(x, 0, 0), cam);
    scene.AddFrame(f);
    first.Integrate(f, cam);
  }
  REQUIRE(scene.submaps() != nullptr);
  CHECK(scene.submaps()->size() == 0);  // one capture: the global TSDF is its submap
  CHECK(scene.keyframe_submaps() == std::vector<int>{-1, -1, -1, -1});
  CHECK_FALSE(scene.uses_submaps());
  for (double x : {0.6, 0.65}) scene.AddFrame(plane.Render(At(x, 0.02, 0), cam));  // 0.45 m jump
  REQUIRE(scene.submaps()->size() == 2);
  CHECK(scene.keyframe_submaps() == std::vector<int>{0, 0, 0, 0, 1, 1});
  CHECK(scene.submaps()->frames_in(0) == 4);
  CHECK(scene.submaps()->frames_in(1) == 2);
  CHECK(scene.submaps()->volume(0).Stats().frames == 4);
  CHECK(scene.tsdf().Stats().frames == 6);
  CHECK(scene.uses_submaps());
  const scene::Pose p = At(0.3, 0.01, 0.1);  // sees what both captures saw
  const cv::Mat copy = scene.submaps()->Raycast({0}, p, cam).depth;
  CHECK(cv::countNonZero(copy > 0.0f) > 0.5 * 40 * 30);
  CHECK(cv::norm(copy, first.Raycast(p, cam).depth, cv::NORM_INF) == 0.0);
  // A third capture starts a third submap.
  scene.AddFrame(plane.Render(At(0.0, 0.4, 0), cam));
  CHECK(scene.submaps()->size() == 3);
  CHECK(scene.keyframe_submaps().back() == 2);
}

TEST_CASE("Submap choice: captures whose poses disagree use their submaps, agreeing ones the global TSDF",
          "[unit]") {
  PlaneScene plane;
  plane.plane_z = 1.0;
  plane.detail = 40.0;
  const auto cam = Cam(96, 72, 90);

  FusionScene off(cam, PerCapture("auto"));
  AddTwoCaptures(plane, cam, 0.15, &off);
  REQUIRE(off.submaps()->size() == 2);
  CHECK_FALSE(off.uses_submaps());  // nothing chosen before Prepare
  off.Prepare();
  const SubmapChoice& a = off.submap_choice();
  INFO(a.Describe());
  CHECK(a.frames == 14);
  CHECK(a.submaps == 2);
  CHECK(a.used);
  CHECK(off.uses_submaps());
  CHECK(a.mse_submaps < 0.9 * a.mse_global);  // twice the margin the choice needs
  CHECK_THAT(off.AutoChoices(), Catch::Contains("submaps auto: used"));

  FusionScene agree(cam, PerCapture("auto"));
  AddTwoCaptures(plane, cam, 0.0, &agree);
  REQUIRE(agree.submaps()->size() == 2);
  agree.Prepare();
  const SubmapChoice& e = agree.submap_choice();
  INFO(e.Describe());
  CHECK(e.frames == 14);
  CHECK_FALSE(e.used);
  CHECK_FALSE(agree.uses_submaps());
  CHECK_THAT(agree.AutoChoices(), Catch::Contains("submaps auto: global"));

  // The scene renders what it chose; a request overrides it.
  const scene::Pose pose = At(0.05, 0.1, 0.0);
  CandidateRequest lean;
  lean.slot_planes = false;
  const ViewCandidates chosen = off.RenderCandidates(pose, cam, lean);
  lean.submaps = false;
  const ViewCandidates global = off.RenderCandidates(pose, cam, lean);
  lean.submaps = true;
  const ViewCandidates local = off.RenderCandidates(pose, cam, lean);
  CHECK(cv::norm(chosen.depth, local.depth, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(chosen.depth, global.depth, cv::NORM_INF) > 0.0);
}

TEST_CASE("Submap choice: one capture or few keyframes keep the global TSDF, YAML and bad values", "[unit]") {
  PlaneScene plane;
  const auto cam = Cam(32, 24, 30);
  FusionScene one(cam, PerCapture("auto"));
  for (double x : {0.0, 0.05, 0.1, 0.15}) one.AddFrame(plane.Render(At(x, 0, 0), cam));
  one.Prepare();
  CHECK(one.submap_choice().frames == 0);
  CHECK(one.submap_choice().submaps == 0);
  CHECK_FALSE(one.uses_submaps());
  CHECK_THROWS_WITH(ChooseSubmaps(one, 16, 160, 1.0), Catch::Contains("min_gain"));
  CHECK_THROWS_WITH(ChooseSubmaps(one, 0), Catch::Contains("max_frames"));

  const SubmapOptions y = SubmapOptions::FromYaml(YAML::Load("{frames: capture, use: auto}"), "test.yaml");
  CHECK(y.per_capture());
  CHECK(y.use == "auto");
  CHECK(y.DescribeFrames() == "capture");
  const SubmapOptions twenty = SubmapOptions::FromYaml(YAML::Load("{frames: 20}"), "test.yaml");
  CHECK(twenty.frames == 20);
  CHECK(twenty.use == "always");
  const SubmapOptions tuned = SubmapOptions::FromYaml(YAML::Load("{break_m: 1.5}"), "test.yaml");
  CHECK(tuned.per_capture());  // over the default
  CHECK(tuned.use == "auto");
  CHECK(tuned.break_m == 1.5);
  CHECK_FALSE(SubmapOptions::FromYaml(YAML::Load("{frames: 0}"), "test.yaml").enabled());
  CHECK(SubmapOptions::FromYaml(YAML::Load("{frames: 20, use: auto}"), "test.yaml").use == "auto");
  CHECK_THROWS_WITH(SubmapOptions::FromYaml(YAML::Load("{use: sometimes}"), "test.yaml"),
                    Catch::Contains("test.yaml") && Catch::Contains("use"));
  CHECK_THROWS_WITH(SubmapOptions::FromYaml(YAML::Load("{frames: captures}"), "test.yaml"),
                    Catch::Contains("test.yaml") && Catch::Contains("frames"));
}

}  // namespace
}  // namespace p2i::fusion
