/// @file submaps_test.cc
/// @brief SubmapSet: frames split into submaps by count and by pose jumps; a view is raycast in
/// the submaps of its keyframes, and the global TSDF fills the rest.
#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/submaps.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

TEST_CASE("SubmapSet: a submap ends after its frame count and at a pose jump", "[unit]") {
  const PlaneScene plane;
  const auto cam = Cam(40, 30, 35);
  SubmapOptions o;
  o.frames = 3;
  o.break_m = 0.5;
  SubmapSet set(o, TsdfOptions{}.ForFrames(cam));
  std::vector<int> ids;
  for (double x : {0.0, 0.05, 0.1, 0.15, 0.2, 1.0, 1.05})  // 1.0: a 0.8 m jump
    ids.push_back(set.Integrate(plane.Render(At(x, 0, 0), cam), cam));
  CHECK(ids == std::vector<int>{0, 0, 0, 1, 1, 2, 2});
  CHECK(set.size() == 3);
  // A frame of another size is refused, naming it, before it can start a submap: the next frame
  // still ends submap 2 at its frame count (it would start submap 3 after an empty one otherwise).
  scene::RgbdSample bad = plane.Render(At(3.0, 0, 0), Cam(20, 15, 18));
  bad.id = "seq-02/frame-4";
  CHECK_THROWS_WITH(set.Integrate(bad, cam), Catch::Contains("seq-02/frame-4"));
  CHECK(set.size() == 3);
  CHECK(set.Integrate(plane.Render(At(1.1, 0, 0), cam), cam) == 2);
  CHECK(set.size() == 3);
  CHECK(set.frames_in(2) == 3);
  CHECK(set.frames_in(1) == 2);
  CHECK(set.Stats().frames == 8);
  // The merged raycast takes the first listed submap with a surface; unknown indices are skipped.
  cv::Mat from;
  const TsdfRaycast r = set.Raycast({7, 2, 0}, At(1.0, 0, 0), cam, &from);
  CHECK(cv::countNonZero(r.depth > 0.0f) > 0.8 * 40 * 30);
  CHECK(cv::countNonZero(from == 2) == cv::countNonZero(r.depth > 0.0f) - cv::countNonZero(from == 3));
  CHECK(cv::countNonZero(from == 1) == 0);
}

TEST_CASE("SubmapSet: an appended (loaded) submap is closed, the next frame starts a new one", "[unit]") {
  const PlaneScene plane;
  const auto cam = Cam(40, 30, 35);
  SubmapOptions o;
  o.frames = 5;
  TsdfVolume loaded{TsdfOptions{}.ForFrames(cam)};
  loaded.Integrate(plane.Render(At(0, 0, 0), cam), cam);
  SubmapSet set(o, TsdfOptions{}.ForFrames(cam));
  set.Append(std::move(loaded), 1);
  set.Prepare();
  CHECK(set.size() == 1);
  CHECK(set.Integrate(plane.Render(At(0.01, 0, 0), cam), cam) == 1);
  CHECK(set.Integrate(plane.Render(At(0.02, 0, 0), cam), cam) == 1);
  CHECK(set.frames_in(0) == 1);
  CHECK(set.volume(0).Stats().frames == 1);
  CHECK_THROWS(set.Append(TsdfVolume{TsdfOptions{}.ForFrames(cam)}, -1));
}

TEST_CASE("FusionScene with submaps: keyframes know their submap, views render from them", "[unit]") {
  const PlaneScene plane;
  const auto cam = Cam(40, 30, 35);
  FusionSceneOptions o;
  o.submaps.frames = 2;
  o.submaps.use = "always";
  FusionScene scene(cam, o);
  for (double x : {0.0, 0.05, 0.1}) scene.AddFrame(plane.Render(At(x, 0, 0), cam));
  REQUIRE(scene.submaps() != nullptr);
  CHECK(scene.keyframe_submaps() == std::vector<int>{0, 0, 1});
  const ViewCandidates c = scene.RenderCandidates(At(0.1, 0, 0), cam);
  const cv::Mat truth = plane.Render(At(0.1, 0, 0), cam).depth;
  CHECK(cv::countNonZero(c.depth > 0.0f) > 0.8 * 40 * 30);
  CHECK(std::abs(c.depth.at<float>(15, 20) - truth.at<float>(15, 20)) < 0.01);
  // By default a submap per capture, kept only from the second capture on; `frames: 0`: none.
  FusionScene plain(cam, FusionSceneOptions{});
  REQUIRE(plain.submaps() != nullptr);
  CHECK(plain.submaps()->options().per_capture());
  CHECK(plain.options().submaps.use == "auto");
  for (double x : {0.0, 0.05, 0.1}) plain.AddFrame(plane.Render(At(x, 0, 0), cam));
  CHECK(plain.submaps()->size() == 0);
  FusionSceneOptions none;
  none.submaps.frames = 0;
  CHECK(FusionScene(cam, none).submaps() == nullptr);
}

TEST_CASE("FusionScene with submaps: the submap integrates beside the global TSDF, as if one after the other",
          "[unit]") {
  PlaneScene plane;
  plane.patch_z = 1.5;
  const auto cam = Cam(64, 48, 55);
  FusionSceneOptions o;
  o.submaps.frames = 3;
  o.submaps.use = "always";
  FusionScene scene(cam, o);
  TsdfVolume global(o.tsdf.ForFrames(cam));
  SubmapSet submaps(o.submaps, o.tsdf.ForFrames(cam));
  for (int i = 0; i < 8; ++i) {
    const scene::RgbdSample f = plane.Render(At(0.04 * i, 0.01 * i, 0), cam);
    scene.Integrate(f);
    global.Integrate(f, cam);
    submaps.Integrate(f, cam);
  }
  REQUIRE(scene.submaps()->size() == submaps.size());
  const scene::Pose p = At(0.13, 0.02, 0.05);
  CHECK(cv::norm(scene.tsdf().Raycast(p, cam).depth, global.Raycast(p, cam).depth, cv::NORM_INF) == 0.0);
  for (size_t m = 0; m < submaps.size(); ++m) {
    INFO("submap " << m);
    CHECK(scene.submaps()->frames_in(m) == submaps.frames_in(m));
    CHECK(cv::norm(scene.submaps()->Raycast({static_cast<int>(m)}, p, cam).depth,
                   submaps.Raycast({static_cast<int>(m)}, p, cam).depth, cv::NORM_INF) == 0.0);
  }
  // A frame neither volume takes is refused, naming it, and leaves the scene usable.
  scene::RgbdSample bad = plane.Render(At(0, 0, 0), Cam(32, 24, 30));
  bad.id = "seq-01/frame-9";
  CHECK_THROWS_WITH(scene.Integrate(bad), Catch::Contains("seq-01/frame-9"));
  scene.Integrate(plane.Render(At(0.1, 0, 0), cam));
  CHECK(scene.tsdf().Stats().frames == 9);
}

TEST_CASE("FillMissingFrom: only the missing pixels, raycast through their rectangle", "[unit]") {
  const PlaneScene plane;
  const auto cam = Cam(40, 30, 35);
  TsdfVolume volume{TsdfOptions{}.ForFrames(cam)};
  for (double x : {0.0, 0.05}) volume.Integrate(plane.Render(At(x, 0, 0), cam), cam);
  const scene::Pose pose = At(0.02, 0, 0);
  const TsdfRaycast full = volume.Raycast(pose, cam);
  REQUIRE(cv::countNonZero(full.depth > 0.0f) > 0.8 * 40 * 30);
  TsdfRaycast into{cv::Mat::zeros(30, 40, CV_32FC1), cv::Mat::zeros(30, 40, CV_32FC3),
                   cv::Mat::zeros(30, 40, CV_32FC3)};
  into.depth(cv::Rect(0, 0, 25, 30)).setTo(5.0f);  // the left 25 columns have a surface already
  cv::Mat filled;
  const int64_t n = FillMissingFrom(volume, pose, cam, &into, &filled);
  const cv::Mat right = full.depth(cv::Rect(25, 0, 15, 30)) > 0.0f;
  CHECK(n == cv::countNonZero(right));
  CHECK(cv::countNonZero(filled) == n);
  CHECK(cv::countNonZero(filled(cv::Rect(0, 0, 25, 30))) == 0);
  CHECK(cv::countNonZero(into.depth(cv::Rect(0, 0, 25, 30)) != 5.0f) == 0);  // left untouched
  double worst = 0.0;
  for (int v = 0; v < 30; ++v)
    for (int u = 25; u < 40; ++u)
      if (full.depth.at<float>(v, u) > 0.0f)
        worst = std::max(worst, std::abs(double(into.depth.at<float>(v, u) - full.depth.at<float>(v, u))));
  CHECK(worst < 1e-4);  // the same surface as the full view's at those pixels
  CHECK(FillMissingFrom(volume, pose, cam, &into) == 0);  // a second call finds nothing more
}

TEST_CASE("SubmapOptions: bad values are refused, naming the key", "[unit]") {
  CHECK_THROWS_WITH(SubmapOptions::FromYaml(YAML::Load("{frames: -1}"), "x.yaml"),
                    Catch::Contains("frames"));
  CHECK_THROWS_WITH(SubmapOptions::FromYaml(YAML::Load("{render: 0}"), "x.yaml"),
                    Catch::Contains("render"));
  CHECK_THROWS_WITH(SubmapOptions::FromYaml(YAML::Load("{breaks: 1}"), "x.yaml"),
                    Catch::Contains("breaks"));
  CHECK(SubmapOptions::FromYaml(YAML::Load("{frames: 40, break_m: 0.3}"), "x.yaml").frames == 40);
}

}  // namespace
}  // namespace p2i::fusion
