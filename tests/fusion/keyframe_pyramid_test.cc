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
  // One kernel for both, so only the level differs (sampling auto would read the full-resolution
  // keyframe bilinearly here, the level bicubically).
  filtered.blend.sampling = raw.blend.sampling = "bicubic";
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

TEST_CASE("DepthPyramid: the nearest valid depth of each 2x2 block, 0 where none is valid",
          "[unit]") {
  cv::Mat d(480, 640, CV_32FC1, cv::Scalar(2.0f));
  d.at<float>(0, 1) = 1.5f;                          // block (0, 0): the nearest wins
  d(cv::Rect(2, 0, 2, 2)).setTo(0.0f);               // block (0, 1): nothing valid
  d(cv::Rect(4, 0, 2, 2)).setTo(0.0f);               // block (0, 2): one valid pixel
  d.at<float>(1, 5) = 3.0f;
  const std::vector<cv::Mat> l = DepthPyramid(d, 3);
  REQUIRE(l.size() == 3);
  for (size_t i = 0; i < l.size(); ++i)  // the colour pyramid's sizes
    CHECK(l[i].size() == ColourPyramid(cv::Mat(480, 640, CV_8UC3), 3)[i].size());
  CHECK(l[0].at<float>(0, 0) == 1.5f);
  CHECK(l[0].at<float>(0, 1) == 0.0f);
  CHECK(l[0].at<float>(0, 2) == 3.0f);
  CHECK(l[0].at<float>(100, 100) == 2.0f);
  CHECK(l[1].at<float>(0, 0) == 1.5f);  // level 2 takes level 1's blocks, invalid ones skipped
  CHECK(DepthPyramid(d, 0).empty());
}

TEST_CASE("FusionScene: a view below the keyframes' resolution tests visibility on the depth "
          "pyramid", "[unit]") {
  // The keyframe's depth is valid on one pixel in four (odd rows and columns): a read of the
  // full-resolution depth at the nearest pixel finds an invalid one three times in four, and
  // that keyframe then does not colour the point. Its depth pyramid is valid everywhere.
  const auto cam = Cam(320, 240, 280);
  const auto view = Cam(80, 60, 70);  // ratio 4: level 2
  const scene::RgbdSample full = PlaneScene().Render(At(0, 0, 0), cam);
  scene::RgbdSample sparse = full;
  sparse.depth = full.depth.clone();
  for (int v = 0; v < cam.image_height; ++v)
    for (int u = 0; u < cam.image_width; ++u)
      if (u % 2 == 0 || v % 2 == 0) sparse.depth.at<float>(v, u) = 0.0f;
  FusionSceneOptions pyramid, raw;
  raw.blend.keyframe_levels = 0;
  FusionScene a(cam, pyramid), b(cam, raw);
  for (FusionScene* fs : {&a, &b}) {
    fs->Integrate(full);           // the geometry from the whole frame
    fs->AddFrame(sparse, false);   // the colour source with the sparse depth
  }
  const ViewCandidates ca = a.RenderCandidates(At(0.01, 0, 0), view);
  const ViewCandidates cb = b.RenderCandidates(At(0.01, 0, 0), view);
  INFO("blended: pyramid " << ca.coverage.blended_fraction << ", full resolution "
                           << cb.coverage.blended_fraction);
  REQUIRE(ca.coverage.observed_fraction > 0.9);
  CHECK(ca.coverage.blended_fraction > 0.9 * ca.coverage.observed_fraction);
  CHECK(cb.coverage.blended_fraction < 0.5 * cb.coverage.observed_fraction);
}

TEST_CASE("UseBicubicRead: bicubic where a view reads its level at about one level pixel per "
          "view pixel", "[unit]") {
  CHECK(UseBicubicRead(100, 100, 100, 100, 0));      // the keyframes' own resolution
  CHECK(UseBicubicRead(200, 200, 100, 100, 0));      // a view above it (magnified)
  CHECK(UseBicubicRead(100, 100, 200, 200, 1));      // 320x240 from 640x480: level 1, 1 left
  CHECK_FALSE(UseBicubicRead(140, 140, 525, 525, 1));  // 128x128 from 640x480: 1.875 left
  CHECK_FALSE(UseBicubicRead(100, 100, 160, 160, 0));  // 1.6: under level 1, skips pixels
  CHECK(UseBicubicRead(100, 100, 140, 140, 0));      // 1.4 < sqrt(2)
  CHECK_FALSE(UseBicubicRead(100, 50, 150, 400, 0));  // the smaller ratio decides: 1.5, not 8
}

TEST_CASE("FusionScene: sampling auto reads bilinear below the keyframes' resolution and "
          "bicubic at it", "[unit]") {
  const auto cam = Cam(320, 240, 280);
  const auto quarter_ish = Cam(96, 72, 84);  // ratio 3.33: level 1, 1.67 left
  const auto same = cam;
  for (const auto& view : {quarter_ish, same}) {
    cv::Mat blended[3];
    const char* modes[3] = {"auto", "bilinear", "bicubic"};
    for (int i = 0; i < 3; ++i) {
      FusionSceneOptions o;
      o.blend.sampling = modes[i];
      FusionScene fs(cam, o);
      fs.AddFrame(NoiseFrame(cam));
      blended[i] = fs.RenderCandidates(At(0.013, 0.007, 0), view).blended;
    }
    INFO("view " << view.image_width << "x" << view.image_height);
    REQUIRE(cv::norm(blended[1], blended[2], cv::NORM_INF) > 0.01);  // the kernels differ here
    const int same_as = view.image_width == cam.image_width ? 2 : 1;
    CHECK(cv::norm(blended[0], blended[same_as], cv::NORM_INF) == 0.0);
  }
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
