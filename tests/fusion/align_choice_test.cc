/// @file align_choice_test.cc
/// @brief `blend.align_iterations: auto` (align_choice.h): the leave-one-out choice turns the
/// slot alignment on where the keyframes' detail lands at different pixels (geometry that is off,
/// as with a real depth sensor) and leaves it off where the geometry is exact.
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/align_choice.h"
#include "fusion/fusion_scene.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

const std::vector<double> kXs = {-0.24, -0.16, -0.08, 0.0, 0.08, 0.16, 0.24};

// Seven keyframes over geometry fused `scale` x too deep (AddOverScaledGeometry).
void AddFrames(const PlaneScene& scene, const scene::CameraInfo& cam, double scale, FusionScene* fs) {
  testing::AddOverScaledGeometry(scene, cam, kXs, scale, fs);
}

// A visibility tolerance wide enough for the off geometry (0.5 m deeper at 2 m), so the slots
// colour it instead of failing their depth test.
FusionSceneOptions Tolerant() {
  FusionSceneOptions o;
  o.blend.visibility_abs_m = 0.6;
  return o;
}

FusionSceneOptions AlignAuto() {
  FusionSceneOptions o = Tolerant();
  o.blend.align.iterations = 1;
  o.blend.align.automatic = true;
  return o;
}

TEST_CASE("Align choice: keyframes misregistered by off geometry turn it on, exact geometry leaves it off", "[unit]") {
  PlaneScene scene;
  scene.detail = 40.0;
  const auto cam = Cam(128, 96, 120);

  FusionScene off_geometry(cam, AlignAuto());
  AddFrames(scene, cam, 1.25, &off_geometry);
  CHECK_FALSE(off_geometry.aligned());  // nothing chosen before Prepare
  off_geometry.Prepare();
  const AlignChoice& a = off_geometry.align_choice();
  INFO(a.Describe());
  CHECK(a.frames == 7);
  CHECK(a.pixels > 7 * 128 * 96 / 2);
  CHECK(a.aligned);
  CHECK(off_geometry.aligned());
  CHECK(a.mse_on < 0.96 * a.mse_off);  // twice the margin the choice needs
  CHECK_THAT(off_geometry.AutoChoices(), Catch::Contains("align auto: on") && Catch::Contains("7 keyframes"));

  FusionScene exact(cam, AlignAuto());
  AddFrames(scene, cam, 1.0, &exact);
  exact.Prepare();
  const AlignChoice& e = exact.align_choice();
  INFO(e.Describe());
  CHECK(e.frames == 7);
  CHECK_FALSE(e.aligned);
  CHECK_FALSE(exact.aligned());
  CHECK(e.mse_off < 0.25 * a.mse_off);  // exact geometry: little for the alignment to fix
  CHECK_THAT(exact.AutoChoices(), Catch::Contains("align auto: off"));
}

TEST_CASE("Align choice: an auto scene renders what it chose, a request overrides it", "[unit]") {
  PlaneScene scene;
  scene.detail = 40.0;
  const auto cam = Cam(128, 96, 120);
  FusionScene fs(cam, AlignAuto());
  AddFrames(scene, cam, 1.25, &fs);
  fs.Prepare();
  REQUIRE(fs.aligned());
  const scene::Pose pose = At(0.04, 0.0, 0.0);
  CandidateRequest lean;
  lean.slot_planes = false;
  const ViewCandidates chosen = fs.RenderCandidates(pose, cam, lean);
  lean.align = true;
  const ViewCandidates on = fs.RenderCandidates(pose, cam, lean);
  lean.align = false;
  const ViewCandidates off = fs.RenderCandidates(pose, cam, lean);
  CHECK(cv::norm(chosen.blended, on.blended, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(chosen.blended, off.blended, cv::NORM_INF) > 0.0);

  // A scene with the alignment off aligns one round when a request asks for it.
  FusionScene plain(cam, Tolerant());
  AddFrames(scene, cam, 1.25, &plain);
  CandidateRequest ask;
  ask.slot_planes = false;
  ask.align = true;
  const ViewCandidates asked = plain.RenderCandidates(pose, cam, ask);
  CHECK(cv::norm(asked.blended, on.blended, cv::NORM_INF) < 1e-6);
}

TEST_CASE("Align choice: few keyframes keep it off, the YAML takes auto, bad arguments are refused", "[unit]") {
  PlaneScene scene;
  const auto cam = Cam(32, 24, 30);
  FusionScene two(cam, AlignAuto());
  two.AddFrame(scene.Render(At(0, 0, 0), cam));
  two.AddFrame(scene.Render(At(0.05, 0, 0), cam));
  two.Prepare();
  CHECK(two.align_choice().frames == 0);
  CHECK_FALSE(two.aligned());
  CHECK_THAT(two.align_choice().Describe(), Catch::Contains("fewer than 3 keyframes"));

  const BlendOptions o = BlendOptions::FromYaml(YAML::Load("{align_iterations: auto}"), "cfg.yaml");
  CHECK(o.align.automatic);
  CHECK(o.align.iterations == 1);
  CHECK_FALSE(BlendOptions::FromYaml(YAML::Load("{align_iterations: 2}"), "cfg.yaml").align.automatic);
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{align_iterations: sometimes}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml") && Catch::Contains("align_iterations"));
  BlendOptions zero;
  zero.align.iterations = 0;
  zero.align.automatic = true;
  CHECK_THROWS_WITH(zero.Validate(), Catch::Contains("at least one round"));
  FusionScene fs(cam, AlignAuto());
  CHECK_THROWS_WITH(ChooseAlignment(fs, 0), Catch::Contains("max_frames"));
  CHECK_THROWS_WITH(ChooseAlignment(fs, 16, 4), Catch::Contains("max_width"));
  CHECK_THROWS_WITH(ChooseAlignment(fs, 16, 160, 1.0), Catch::Contains("min_gain"));
}

}  // namespace
}  // namespace p2i::fusion
