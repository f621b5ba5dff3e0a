/// @file message_conversion_test.cc
/// @brief View / RgbdFrame messages to SinkFrame: depth encodings, invalid values, stamps.
#include "nodes/slam_sink/message_conversion.h"

#include <cstring>

#include <catch2/catch.hpp>

namespace p2i::slam_sink {
namespace {

TEST_CASE("Message images convert to RGB and metric depth, invalid values to 0", "[unit]") {
  msgs::Image depth16 = msgs::Image::Allocate(msgs::pb::DEPTH16U, 3, 2);
  depth16.depth_scale = 0.001;
  depth16.invalid_value = 65535;
  const uint16_t values[6] = {1000, 0, 65535, 2500, 1, 4000};
  std::memcpy(depth16.MutableData(), values, sizeof(values));
  const cv::Mat m = ImageToMat(depth16, true);
  REQUIRE(m.type() == CV_32FC1);
  CHECK(m.at<float>(0, 0) == Approx(1.0));
  CHECK(m.at<float>(0, 1) == 0.0f);
  CHECK(m.at<float>(0, 2) == 0.0f);  // the declared invalid value
  CHECK(m.at<float>(1, 0) == Approx(2.5));
  CHECK(m.at<float>(1, 2) == Approx(4.0));

  msgs::Image rgb = msgs::Image::Allocate(msgs::pb::RGB8, 2, 1);
  rgb.MutableData()[0] = 10;
  rgb.MutableData()[5] = 200;
  const cv::Mat c = ImageToMat(rgb, false);
  REQUIRE(c.type() == CV_8UC3);
  CHECK(c.at<cv::Vec3b>(0, 0)[0] == 10);
  CHECK(c.at<cv::Vec3b>(0, 1)[2] == 200);
  CHECK_THROWS_AS(ImageToMat(rgb, true), std::invalid_argument);
  CHECK_THROWS_AS(ImageToMat(msgs::Image{}, false), std::invalid_argument);
}

TEST_CASE("FrameFromView takes stamp, pose, seq and source from the message", "[unit]") {
  msgs::View view;
  view.meta.mutable_header()->set_capture_stamp_ns(1234500000000LL);
  view.meta.mutable_header()->set_seq(42);
  view.meta.mutable_header()->set_publisher("/synthesizer");
  msgs::SetPose({1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0}, view.meta.mutable_pose());
  view.meta.set_coverage(0.8);
  view.rgb = msgs::Image::Allocate(msgs::pb::RGB8, 4, 4);
  view.depth = msgs::Image::Allocate(msgs::pb::DEPTH32F, 4, 4);
  view.depth.depth_scale = 1.0;
  const SinkFrame f = FrameFromView(view, "/views");
  CHECK(f.stamp == Approx(1234.5));
  CHECK(f.seq == 42);
  CHECK(f.source == "/synthesizer@/views");
  CHECK(f.synthetic);
  CHECK(f.coverage == Approx(0.8));
  CHECK(f.pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  CHECK(f.depth.type() == CV_32FC1);
}

}  // namespace
}  // namespace p2i::slam_sink
