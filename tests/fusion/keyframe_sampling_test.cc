/// @file keyframe_sampling_test.cc
/// @brief The blend's keyframe reads (fusion/keyframe_sampling.h): every kernel exact at pixel
/// centres, the bilinear and Catmull-Rom on linear ramps too; the bicubic keeps more of a
/// one-pixel feature than the bilinear, a = -0.75 more than Catmull-Rom; BlendOptions::sampling
/// and ::cubic_a are read, checked and change what the blend reads.
#include <catch2/catch.hpp>

#include <yaml-cpp/yaml.h>

#include "fusion/fusion_scene.h"
#include "fusion/keyframe_sampling.h"
#include "tests/fusion/fusion_test_util.h"

namespace p2i::fusion {
namespace {

TEST_CASE("keyframe sampling: exact at pixel centres and on linear ramps", "[unit]") {
  cv::Mat noise(9, 11, CV_8UC3);
  cv::randu(noise, 0, 256);
  for (int y = 0; y < noise.rows; ++y) {
    for (int x = 0; x < noise.cols; ++x) {
      const cv::Vec3b p = noise.at<cv::Vec3b>(y, x);
      const float fx = static_cast<float>(x), fy = static_cast<float>(y);
      const cv::Vec3f a = SampleBilinear(noise, fx, fy);
      const cv::Vec3f b = SampleBicubic(noise, fx, fy, kCatmullRomA);
      const cv::Vec3f b75 = SampleBicubic(noise, fx, fy, -0.75f);
      for (int c = 0; c < 3; ++c) {
        CHECK(a[c] == Approx(p[c] / 255.0f).margin(1e-6));
        CHECK(b[c] == Approx(p[c] / 255.0f).margin(1e-6));
        CHECK(b75[c] == Approx(p[c] / 255.0f).margin(1e-6));
      }
    }
  }
  // A ramp 8 x + 12 y (+ channel offsets; at most 185), read between pixels away from the border.
  cv::Mat ramp(9, 11, CV_8UC3);
  for (int y = 0; y < ramp.rows; ++y)
    for (int x = 0; x < ramp.cols; ++x)
      ramp.at<cv::Vec3b>(y, x) = cv::Vec3b(8 * x + 12 * y, 8 * x + 12 * y + 5, 8 * x + 12 * y + 9);
  for (const float x : {1.25f, 3.5f, 7.9f}) {
    for (const float y : {1.1f, 4.5f, 6.75f}) {
      const cv::Vec3f a = SampleBilinear(ramp, x, y);
      const cv::Vec3f b = SampleBicubic(ramp, x, y, kCatmullRomA);
      for (int c = 0; c < 3; ++c) {
        const float want = (8.0f * x + 12.0f * y + (c == 0 ? 0.0f : c == 1 ? 5.0f : 9.0f)) / 255.0f;
        CHECK(a[c] == Approx(want).margin(1e-5));
        CHECK(b[c] == Approx(want).margin(1e-5));
      }
    }
  }
  // Every a sums to 1 (a flat image stays flat); only Catmull-Rom's first moment is the offset
  // (a ramp read where it is), a = -0.75 reads a ramp 0.042 px off at t = 0.3.
  for (const float a : {-0.5f, -0.75f, -1.0f}) {
    float w[4];
    CubicWeights(0.3f, a, w);
    CHECK(w[0] + w[1] + w[2] + w[3] == Approx(1.0f).margin(1e-6));
    const float centre = -w[0] + w[2] + 2.0f * w[3];
    CHECK(centre == Approx(a == -0.5f ? 0.3f : a == -0.75f ? 0.342f : 0.384f).margin(1e-5));
  }
}

TEST_CASE("keyframe sampling: the bicubic keeps more of a one-pixel line, clamped to [0, 1]",
          "[unit]") {
  cv::Mat line(8, 8, CV_8UC3, cv::Scalar::all(0));
  line.col(3).setTo(cv::Scalar::all(255));
  // Half a pixel beside the line: the bilinear read halves it, the bicubic keeps 9/16.
  CHECK(SampleBilinear(line, 3.5f, 4.0f)[0] == Approx(0.5f).margin(1e-6));
  CHECK(SampleBicubic(line, 3.5f, 4.0f, kCatmullRomA)[0] == Approx(0.5625f).margin(1e-6));
  CHECK(SampleBicubic(line, 2.5f, 4.0f, kCatmullRomA)[1] == Approx(0.5625f).margin(1e-6));
  // Keys' a = -0.75 (OpenCV's INTER_CUBIC) keeps 19/32, with a deeper negative lobe beside it.
  CHECK(SampleBicubic(line, 3.5f, 4.0f, -0.75f)[0] == Approx(0.59375f).margin(1e-6));
  // One pixel further the cubic's negative lobe would go below 0: clamped.
  CHECK(SampleBicubic(line, 4.5f, 4.0f, kCatmullRomA)[2] == 0.0f);
  // At the image corner the taps repeat the edge pixels.
  CHECK(SampleBicubic(line, 0.0f, 0.0f, kCatmullRomA)[0] == 0.0f);
  CHECK(SampleBicubic(line, 7.0f, 7.0f, kCatmullRomA)[0] == 0.0f);
}

TEST_CASE("BlendOptions: sampling is read, checked, and changes the blend", "[unit]") {
  CHECK(BlendOptions().sampling == "auto");
  CHECK(BlendOptions().cubic_a == -0.75);
  CHECK(BlendOptions::FromYaml(YAML::Load("{cubic_a: -0.5}"), "test.yaml").cubic_a == -0.5);
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{cubic_a: 0.5}"), "test.yaml"),
                    Catch::Contains("cubic_a must be in [-1, 0]") && Catch::Contains("test.yaml"));
  CHECK(BlendOptions::FromYaml(YAML::Load("{sampling: bilinear}"), "test.yaml").sampling ==
        "bilinear");
  CHECK_THROWS_WITH(BlendOptions::FromYaml(YAML::Load("{sampling: nearest}"), "test.yaml"),
                    Catch::Contains("sampling must be auto, bicubic or bilinear, got 'nearest'") &&
                        Catch::Contains("test.yaml"));
  // A view between the keyframes reads them at fractional positions: the kernels differ there,
  // by little on this smooth texture.
  const testing::PlaneScene plane;
  const auto cam = testing::Cam(80, 60, 70);
  cv::Mat blended[3];
  for (int i = 0; i < 3; ++i) {
    FusionSceneOptions o;
    o.blend.sampling = i == 0 ? "bilinear" : "bicubic";
    if (i == 1) o.blend.cubic_a = -0.5;  // i == 2: the default, -0.75
    FusionScene fs(cam, o);
    for (double x : {-0.1, 0.0, 0.1}) fs.AddFrame(plane.Render(testing::At(x, 0, 0), cam));
    blended[i] = fs.RenderCandidates(testing::At(0.0237, 0.0113, 0), cam).blended;
  }
  for (int i : {1, 2}) {
    cv::Mat diff;
    cv::absdiff(blended[i - 1], blended[i], diff);
    double max_diff = 0.0;
    cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
    CHECK(max_diff > 1e-3);           // the texture's curvature between pixels
    CHECK(cv::mean(diff)[0] < 0.01);  // a smooth texture: the same image otherwise
  }
}

}  // namespace
}  // namespace p2i::fusion
