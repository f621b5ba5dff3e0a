/// @file message_conversion_test.cc
/// @brief View / RgbdFrame messages to SinkFrame: metric depth as every node decodes it, stamps.
#include "nodes/slam_sink/message_conversion.h"

#include <cstring>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "convert/depth.h"
#include "convert/pose.h"
#include "convert/rgbd_frame.h"

namespace p2i::slam_sink {
namespace {

msgs::RgbdFrame FrameWithDepth(msgs::Image depth) {
  msgs::RgbdFrame f;
  f.meta.mutable_header()->set_capture_stamp_ns(1000000000LL);
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, depth.width, depth.height);
  f.depth = std::move(depth);
  return f;
}

TEST_CASE("Sink frames carry metric depth by p2i.proto, the same as the trainer's samples",
          "[unit]") {
  // 16-bit at 1 mm with 65535 invalid, and float at 0.5 m per unit with -1 invalid: the sink
  // must decode both as convert::ToSample (the trainer) and convert::DepthToMetres (monitor) do.
  msgs::Image depth16 = msgs::Image::Allocate(msgs::pb::DEPTH16U, 3, 2);
  depth16.depth_scale = 0.001;
  depth16.invalid_value = 65535;
  const uint16_t values16[6] = {1000, 0, 65535, 2500, 1, 4000};
  std::memcpy(depth16.MutableData(), values16, sizeof(values16));
  msgs::Image depth32 = msgs::Image::Allocate(msgs::pb::DEPTH32F, 3, 2);
  depth32.depth_scale = 0.5;
  depth32.invalid_value = -1.0;
  const float values32[6] = {2.0f, 0.0f, -1.0f, 5.0f, 0.002f, 8.0f};
  std::memcpy(depth32.MutableData(), values32, sizeof(values32));

  for (const msgs::Image& depth : {depth16, depth32}) {
    const msgs::RgbdFrame frame = FrameWithDepth(depth);
    const SinkFrame f = FrameFromRgbd(frame, "/rgbd");
    REQUIRE(f.depth.type() == CV_32FC1);
    CHECK(f.depth.at<float>(0, 0) == Approx(1.0));
    CHECK(f.depth.at<float>(0, 1) == 0.0f);
    CHECK(f.depth.at<float>(0, 2) == 0.0f);  // the declared invalid value
    CHECK(f.depth.at<float>(1, 0) == Approx(2.5));
    CHECK(f.depth.at<float>(1, 2) == Approx(4.0));
    CHECK(cv::norm(f.depth, convert::ToSample(frame).depth, cv::NORM_INF) == 0.0);
    CHECK(cv::norm(f.depth, convert::DepthToMetres(frame.depth), cv::NORM_INF) == 0.0);
  }
  msgs::RgbdFrame bad = FrameWithDepth(depth16);
  bad.rgb = msgs::Image::Allocate(msgs::pb::MONO8, 3, 2);
  CHECK_THROWS_AS(FrameFromRgbd(bad, "/rgbd"), std::invalid_argument);
}

TEST_CASE("FrameFromView takes stamp, pose, seq and source from the message", "[unit]") {
  msgs::View view;
  view.meta.mutable_header()->set_capture_stamp_ns(1234500000000LL);
  view.meta.mutable_header()->set_seq(42);
  view.meta.mutable_header()->set_publisher("/synthesizer");
  convert::SetPose({1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0}, view.meta.mutable_pose());
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
