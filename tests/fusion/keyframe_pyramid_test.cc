/// @file keyframe_pyramid_test.cc
/// @brief The keyframes' colour pyramid: which level a view reads, the coordinate mapping, and
/// that a view below the keyframes' resolution reads pre-filtered colour (no aliasing) while a
/// view at their resolution is unchanged.
#include <random>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/keyframe_pyramid.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

using testing::At;
using testing::Cam;
using testing::PlaneScene;

TEST_CASE("PyramidLevelFor: the level nearest at or above the view's focal length", "[unit]") {
  CHECK(PyramidLevelFor(100, 100, 100, 100, 3) == 0);  // same resolution
  CHECK(PyramidLevelFor(200, 200, 100, 100, 3) == 0);  // view above the keyframes
  CHECK(PyramidLevelFor(100, 100, 199, 199, 3) == 0);  // level 1 would magnify
  CHECK(PyramidLevelFor(100, 100, 200, 200, 3) == 1);  // 320x240 from 640x480
  CHECK(PyramidLevelFor(105, 105, 525, 525, 3) == 2);  // 128x128 from 640x480: 131 >= 105
  CHECK(PyramidLevelFor(10, 10, 525, 525, 3) == 3);    // capped
  CHECK(PyramidLevelFor(10, 10, 525, 525, 0) == 0);    // pyramid off
  CHECK(PyramidLevelFor(100, 50, 400, 100, 3) == 1);   // the smaller ratio decides
}

TEST_CASE("ToPyramidLevel: pixel centres map to pixel centres, clamped to the level", "[unit]") {
  float x = 0.5f, y = 2.5f;  // between level-0 pixels 0|1 and 2|3: level-1 pixels 0 and 1
  ToPyramidLevel(1, 10, 10, &x, &y);
  CHECK(x == Approx(0.0f));
  CHECK(y == Approx(1.0f));
  x = 1.5f, y = 0.0f;  // centre of the level-2 pixel 0 is level-0 1.5
  ToPyramidLevel(2, 10, 10, &x, &y);
  CHECK(x == Approx(0.0f));
  CHECK(y == Approx(0.0f));  // -0.375 clamped
  x = 39.0f, y = 3.5f;
  ToPyramidLevel(2, 10, 10, &x, &y);
  CHECK(x == Approx(9.0f));  // 9.375 clamped to w - 1
  CHECK(y == Approx(0.5f));
  x = 7.25f, y = 3.75f;
  ToPyramidLevel(0, 4, 4, &x, &y);  // level 0: unchanged, even outside
  CHECK(x == 7.25f);
  CHECK(y == 3.75f);
}

TEST_CASE("ColourPyramid: halves each level and stops before a side under 8 pixels", "[unit]") {
  const cv::Mat rgb(480, 640, CV_8UC3, cv::Scalar(10, 20, 30));
  const std::vector<cv::Mat> l = ColourPyramid(rgb, 3);
  REQUIRE(l.size() == 3);
  CHECK(l[0].size() == cv::Size(320, 240));
  CHECK(l[2].size() == cv::Size(80, 60));
  CHECK(l[2].at<cv::Vec3b>(30, 40) == cv::Vec3b(10, 20, 30));  // a flat image stays flat
  CHECK(ColourPyramid(cv::Mat(20, 40, CV_8UC3, cv::Scalar::all(0)), 5).size() == 1);  // 20x10, then 10x5
  CHECK(ColourPyramid(rgb, 0).empty());
}

// A keyframe of the plane whose colour is per-pixel noise: its correct low-pass at a quarter of
// the resolution is nearly flat, an unfiltered read keeps the noise (aliasing).
scene::RgbdSample NoiseFrame(const scene::CameraInfo& cam) {
  scene::RgbdSample f = PlaneScene().Render(At(0, 0, 0), cam);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grey(0, 255);
  for (int v = 0; v < f.rgb.rows; ++v)
    for (int u = 0; u < f.rgb.cols; ++u) f.rgb.at<cv::Vec3b>(v, u) = cv::Vec3b::all(static_cast<uint8_t>(grey(rng)));
  return f;
}

// Standard deviation of the blended colour's first channel over the observed pixels.
double BlendStd(FusionScene* fs, const scene::CameraInfo& view_cam) {
  const ViewCandidates c = fs->RenderCandidates(At(0, 0, 0), view_cam);
  REQUIRE(c.coverage.observed_fraction > 0.9);
  std::vector<cv::Mat> ch;
  cv::split(c.blended, ch);
  cv::Scalar mean, sd;
  cv::meanStdDev(ch[0], mean, sd, c.observed);
  CHECK(mean[0] == Approx(0.5).margin(0.05));
  return sd[0];
}

TEST_CASE("FusionScene: a view at a quarter of the keyframes' resolution reads the pre-filtered "
          "level, not aliased full-resolution colour", "[unit]") {
  const auto cam = Cam(320, 240, 280);
  const auto view = Cam(80, 60, 70);  // ratio 4: level 2
  FusionSceneOptions filtered, raw;
  raw.blend.keyframe_levels = 0;
  FusionScene a(cam, filtered), b(cam, raw);
  a.AddFrame(NoiseFrame(cam));
  b.AddFrame(NoiseFrame(cam));
  const double sd_filtered = BlendStd(&a, view), sd_raw = BlendStd(&b, view);
  INFO("std filtered " << sd_filtered << ", unfiltered " << sd_raw);
  CHECK(sd_raw > 0.15);                    // uniform noise: std 0.29, a bicubic read keeps most
  CHECK(sd_filtered < 0.5 * sd_raw);  // two 2x2 means: a 4x4 box, std / 4 = 0.072
}

TEST_CASE("FusionScene: a view at the keyframes' own resolution reads them unfiltered whatever "
          "keyframe_levels says", "[unit]") {
  const auto cam = Cam(80, 60, 70);
  FusionSceneOptions filtered, raw;
  raw.blend.keyframe_levels = 0;
  FusionScene a(cam, filtered), b(cam, raw);
  a.AddFrame(NoiseFrame(cam));
  b.AddFrame(NoiseFrame(cam));
  const ViewCandidates ca = a.RenderCandidates(At(0.01, 0, 0), cam);
  const ViewCandidates cb = b.RenderCandidates(At(0.01, 0, 0), cam);
  CHECK(cv::norm(ca.blended, cb.blended, cv::NORM_INF) == 0.0);
}

TEST_CASE("BlendOptions: keyframe_levels outside [0, 6] is refused by name", "[unit]") {
  BlendOptions o;
  o.keyframe_levels = 7;
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("keyframe_levels"));
  o.keyframe_levels = -1;
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("keyframe_levels"));
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{keyframe_levels: 9}"), "cfg.yaml"),
                    Catch::Contains("cfg.yaml") && Catch::Contains("keyframe_levels"));
}

}  // namespace
}  // namespace p2i::fusion
