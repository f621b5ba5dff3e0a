/// @file image_ops_test.cc
/// @brief Centre crop + resize of RGB-D samples and the matching intrinsics.
#include <cmath>
#include <set>

#include <catch2/catch.hpp>

#include "scene/image_ops.h"
#include "tests/scene/dataset_test_util.h"

namespace p2i::scene {
namespace {

TEST_CASE("CenterCropRect takes the largest centred window of the target aspect", "[unit]") {
  CHECK(CenterCropRect(640, 480, 128, 128) == cv::Rect(80, 0, 480, 480));
  CHECK(CenterCropRect(480, 640, 128, 128) == cv::Rect(0, 80, 480, 480));
  CHECK(CenterCropRect(640, 480, 320, 240) == cv::Rect(0, 0, 640, 480));
  CHECK(CenterCropRect(640, 480, 256, 128) == cv::Rect(0, 80, 640, 320));
  CHECK_THROWS_AS(CenterCropRect(640, 480, 0, 128), std::invalid_argument);
}

TEST_CASE("Depth is resized with nearest neighbour: no blends across edges or holes", "[unit]") {
  RgbdSample s;
  s.rgb = cv::Mat(480, 640, CV_8UC3, cv::Scalar(1, 2, 3));
  s.depth = cv::Mat(480, 640, CV_32FC1);
  // Left half 1 m, right half 4 m, and a checkerboard of holes in the top-left quarter.
  for (int r = 0; r < 480; ++r) {
    for (int c = 0; c < 640; ++c) {
      float d = c < 320 ? 1.0f : 4.0f;
      if (r < 240 && c < 320 && ((r / 3 + c / 3) % 2 == 0)) d = 0.0f;
      s.depth.at<float>(r, c) = d;
    }
  }
  const RgbdSample out = CenterCropResizeSample(s, 128, 128);
  REQUIRE(out.rgb.size() == cv::Size(128, 128));
  REQUIRE(out.depth.size() == cv::Size(128, 128));
  REQUIRE(out.depth.type() == CV_32FC1);
  std::set<float> values;
  for (int r = 0; r < 128; ++r) {
    for (int c = 0; c < 128; ++c) values.insert(out.depth.at<float>(r, c));
  }
  CHECK(values == std::set<float>{0.0f, 1.0f, 4.0f});
  CHECK(out.rgb.at<cv::Vec3b>(64, 64) == cv::Vec3b(1, 2, 3));
}

TEST_CASE("Depth and colour are resized onto the same pixel centres (depth takes the source pixel under each output centre)", "[unit]") {
  // depth = the source column (and row) index, rgb = a sharp vertical edge: after the resize the
  // depth at output pixel x is the source pixel under x's centre, (x + 0.5) * scale - 0.5 rounded,
  // as the colour's centre-aligned resize and CameraInfo::Scaled place it. OpenCV's INTER_NEAREST
  // took floor(x * scale) instead: 1.4 source pixels (0.37 output pixels) off at 480 -> 128.
  RgbdSample s;
  s.rgb = cv::Mat(480, 480, CV_8UC3, cv::Scalar(0, 0, 0));
  s.depth = cv::Mat(480, 480, CV_32FC1);
  for (int r = 0; r < 480; ++r)
    for (int c = 0; c < 480; ++c) s.depth.at<float>(r, c) = 1.0f + c + 1000.0f * r;
  const RgbdSample out = ResizeSample(s, 128, 128);
  const double scale = 480.0 / 128.0;
  for (int x : {0, 1, 17, 64, 100, 127}) {
    const double centre = (x + 0.5) * scale - 0.5;  // source coordinate of the output centre
    const float d = out.depth.at<float>(x, x);
    const double col = std::fmod(d - 1.0, 1000.0), row = std::floor((d - 1.0) / 1000.0);
    INFO("output pixel " << x << ": source column " << col << ", centre " << centre);
    CHECK(std::abs(col - centre) <= 0.5 + 1e-9);
    CHECK(std::abs(row - centre) <= 0.5 + 1e-9);
  }
}

TEST_CASE("Centre crop keeps the centre pixel and the camera sees it at the same place",
          "[unit]") {
  RgbdSample s = p2i::testing::MakeSample(640, 480, 0, 1.5, p2i::testing::MakePose(0.3, 10));
  s.id = "x";
  // A marker around the image centre survives crop + resize at the output centre.
  s.rgb(cv::Rect(300, 220, 40, 40)).setTo(cv::Scalar(255, 0, 0));
  const RgbdSample out = CenterCropResizeSample(s, 128, 128);
  CHECK(out.rgb.at<cv::Vec3b>(64, 64) == cv::Vec3b(255, 0, 0));
  CHECK(out.rgb.at<cv::Vec3b>(10, 10) != cv::Vec3b(255, 0, 0));
  CHECK(out.id == "x");
  CHECK(out.stamp == 1.5);
  CHECK(out.pose.equals(s.pose));

  const CameraInfo cam = CameraInfo::Pinhole(640, 480, 525.0, 525.0, 319.5, 239.5);
  const CameraInfo small = CenterCropResizeCamera(cam, 128, 128);
  CHECK(small.image_width == 128);
  CHECK(small.image_height == 128);
  // 480 pixels -> 128: focal scales by 128/480.
  CHECK(small.fx() == Approx(525.0 * 128.0 / 480.0).epsilon(1e-6));
  CHECK(small.fy() == Approx(525.0 * 128.0 / 480.0).epsilon(1e-6));
  // Centre crop 480x480 at x0 = 80, then the pixel-centre convention: (319.5 - 80 + 0.5) * s - 0.5.
  CHECK(small.cx() == Approx((319.5 - 80 + 0.5) * 128.0 / 480.0 - 0.5));  // = 63.5
  CHECK(small.cy() == Approx(63.5));
  CHECK(small.equals(cam.Cropped(80, 0, 480, 480).Scaled(128, 128), 1e-12));
  // Same aspect ratio: only scaling.
  CHECK(CenterCropResizeCamera(cam, 320, 240).equals(cam.Scaled(320, 240), 1e-12));
  // Taller target (1:2): crop 240x480 at x0 = 200.
  CHECK(CenterCropResizeCamera(cam, 64, 128)
            .equals(cam.Cropped(200, 0, 240, 480).Scaled(64, 128), 1e-12));
  CHECK_THROWS_AS(CenterCropResizeCamera(cam, 0, 128), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::scene
