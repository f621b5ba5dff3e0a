/// @file image_test.cc
/// @brief ToImage / ToMat / RgbToMat: packing, views without copies, encoding checks.
#include "convert/image.h"

#include <stdexcept>

#include <catch2/catch.hpp>

namespace p2i::convert {
namespace {

TEST_CASE("ToImage packs RGB and metric depth, ToMat views them back", "[unit]") {
  cv::Mat rgb(2, 3, CV_8UC3, cv::Scalar(10, 20, 30));
  rgb.at<cv::Vec3b>(1, 2) = cv::Vec3b(200, 100, 50);
  const msgs::Image a = ToImage(rgb);
  CHECK(a.encoding == msgs::pb::RGB8);
  CHECK(a.width == 3);
  CHECK(a.height == 2);
  CHECK(cv::norm(ToMat(a), rgb, cv::NORM_L1) == 0.0);

  cv::Mat depth(2, 3, CV_32FC1, cv::Scalar(1.5f));
  const msgs::Image d = ToImage(depth);
  CHECK(d.encoding == msgs::pb::DEPTH32F);
  CHECK(d.depth_scale == 1.0);
  CHECK(d.invalid_value == 0.0);
  const cv::Mat view = ToMat(d);
  CHECK(view.data == d.data->data());  // a view, not a copy
  CHECK(view.at<float>(1, 2) == 1.5f);

  CHECK_THROWS_AS(ToImage(cv::Mat(2, 2, CV_16UC1)), std::invalid_argument);
}

TEST_CASE("RgbToMat copies RGB8 and names any other encoding", "[unit]") {
  msgs::Image rgb = msgs::Image::Allocate(msgs::pb::RGB8, 2, 1);
  rgb.MutableData()[0] = 10;
  rgb.MutableData()[5] = 200;
  const cv::Mat c = RgbToMat(rgb);
  REQUIRE(c.type() == CV_8UC3);
  CHECK(c.data != rgb.data->data());  // owned
  CHECK(c.at<cv::Vec3b>(0, 0)[0] == 10);
  CHECK(c.at<cv::Vec3b>(0, 1)[2] == 200);
  CHECK_THROWS_WITH(RgbToMat(msgs::Image::Allocate(msgs::pb::DEPTH32F, 2, 2)),
                    Catch::Contains("DEPTH32F"));
  msgs::Image empty;
  empty.encoding = msgs::pb::RGB8;
  CHECK_THROWS_AS(RgbToMat(empty), std::invalid_argument);
  CHECK_THROWS_AS(ToMat(msgs::Image{}), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::convert
