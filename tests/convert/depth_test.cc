/// @file depth_test.cc
/// @brief DepthToMetres: both encodings, depth_scale, the invalid value, non-finite values.
#include "convert/depth.h"

#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include <catch2/catch.hpp>

namespace p2i::convert {
namespace {

template <class T>
msgs::Image DepthImage(msgs::Encoding encoding, const std::vector<T>& v, int w, double scale,
                       double invalid) {
  msgs::Image img = msgs::Image::Allocate(encoding, w, v.size() / w);
  img.depth_scale = scale;
  img.invalid_value = invalid;
  std::memcpy(img.MutableData(), v.data(), v.size() * sizeof(T));
  return img;
}

msgs::Image Depth16(const std::vector<uint16_t>& v, int w, double scale, double invalid) {
  return DepthImage(msgs::pb::DEPTH16U, v, w, scale, invalid);
}

msgs::Image Depth32(const std::vector<float>& v, int w, double scale, double invalid) {
  return DepthImage(msgs::pb::DEPTH32F, v, w, scale, invalid);
}

TEST_CASE("DEPTH16U: metres = value x depth_scale, the invalid value and 0 give 0", "[unit]") {
  const cv::Mat m = DepthToMetres(Depth16({1000, 0, 65535, 2500, 1, 4000}, 3, 0.001, 65535));
  REQUIRE(m.type() == CV_32FC1);
  REQUIRE(m.size() == cv::Size(3, 2));
  CHECK(m.at<float>(0, 0) == Approx(1.0));
  CHECK(m.at<float>(0, 1) == 0.0f);  // 0 m is no measurement
  CHECK(m.at<float>(0, 2) == 0.0f);  // the declared invalid value
  CHECK(m.at<float>(1, 0) == Approx(2.5));
  CHECK(m.at<float>(1, 1) == Approx(0.001));
  CHECK(m.at<float>(1, 2) == Approx(4.0));
  // TUM's 1/5000 scale.
  CHECK(DepthToMetres(Depth16({5000}, 1, 1.0 / 5000, 0)).at<float>(0, 0) == Approx(1.0));
}

TEST_CASE("DEPTH32F: depth_scale and invalid_value apply as for 16-bit depth", "[unit]") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const cv::Mat m = DepthToMetres(Depth32({2.0f, -1.0f, 3.0f, nan, inf, -2.0f}, 3, 0.5, -1.0));
  CHECK(m.at<float>(0, 0) == Approx(1.0));  // 2 x 0.5
  CHECK(m.at<float>(0, 1) == 0.0f);         // the declared invalid value
  CHECK(m.at<float>(0, 2) == Approx(1.5));
  CHECK(m.at<float>(1, 0) == 0.0f);         // NaN
  CHECK(m.at<float>(1, 1) == 0.0f);         // inf
  CHECK(m.at<float>(1, 2) == 0.0f);         // negative metres
  // The common case: scale 1, invalid 0.
  CHECK(DepthToMetres(Depth32({1.25f, 0.0f}, 2, 1.0, 0.0)).at<float>(0, 0) == 1.25f);
}

TEST_CASE("The two encodings of one depth give the same metres", "[unit]") {
  // A producer at 2 mm per unit and one sending float metres x 0.25: the same scene depth.
  const cv::Mat a = DepthToMetres(Depth16({500, 1000, 0, 1500}, 2, 0.002, 0));
  const cv::Mat b = DepthToMetres(Depth32({4.0f, 8.0f, 99.0f, 12.0f}, 2, 0.25, 99.0));
  REQUIRE(a.size() == b.size());
  for (int i = 0; i < 4; ++i) CHECK(a.at<float>(i / 2, i % 2) == Approx(b.at<float>(i / 2, i % 2)));
  CHECK(a.at<float>(1, 0) == 0.0f);
}

TEST_CASE("DepthToMetres honours the row step and refuses non-depth images", "[unit]") {
  msgs::Image padded = msgs::Image::Allocate(msgs::pb::DEPTH16U, 2, 2);
  padded.step = 8;  // 4 bytes of payload + 4 of padding per row
  padded.data = std::make_shared<const msgs::Bytes>(16, 0);
  const uint16_t row1[2] = {3000, 4000};
  std::memcpy(padded.MutableData() + 8, row1, sizeof(row1));
  padded.depth_scale = 0.001;
  const cv::Mat m = DepthToMetres(padded);
  CHECK(m.at<float>(1, 0) == Approx(3.0));
  CHECK(m.at<float>(1, 1) == Approx(4.0));
  CHECK(m.isContinuous());

  CHECK_THROWS_AS(DepthToMetres(msgs::Image::Allocate(msgs::pb::RGB8, 2, 2)),
                  std::invalid_argument);
  CHECK_THROWS_WITH(DepthToMetres(msgs::Image::Allocate(msgs::pb::MONO16, 2, 2)),
                    Catch::Contains("MONO16"));
  msgs::Image empty;
  empty.encoding = msgs::pb::DEPTH32F;
  CHECK_THROWS_WITH(DepthToMetres(empty), Catch::Contains("no data"));
}

}  // namespace
}  // namespace p2i::convert
