/// @file rgbd_frame_test.cc
/// @brief ToSample: an RgbdFrame message as a scene sample (stamp, id, pose, metric depth).
#include "convert/rgbd_frame.h"

#include <cstring>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "convert/pose.h"

namespace p2i::convert {
namespace {

TEST_CASE("ToSample takes stamp, seq and pose and decodes depth to metres", "[unit]") {
  msgs::RgbdFrame f;
  f.meta.mutable_header()->set_capture_stamp_ns(2500000000LL);
  f.meta.mutable_header()->set_seq(7);
  SetPose({1, 2, 3, 0, 0, 0, 1}, f.meta.mutable_pose());
  f.rgb = msgs::Image::Allocate(msgs::pb::RGB8, 2, 1);
  f.rgb.MutableData()[3] = 99;
  f.depth = msgs::Image::Allocate(msgs::pb::DEPTH32F, 2, 1);
  f.depth.depth_scale = 0.5;  // not 1: must be applied (the trainer used to ignore it)
  f.depth.invalid_value = 7.0;
  const float d[2] = {3.0f, 7.0f};
  std::memcpy(f.depth.MutableData(), d, sizeof(d));
  const scene::RgbdSample s = ToSample(f);
  CHECK(s.stamp == Approx(2.5));
  CHECK(s.id == "7");
  CHECK(s.pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  CHECK(s.rgb.at<cv::Vec3b>(0, 1)[0] == 99);
  CHECK(s.depth.at<float>(0, 0) == Approx(1.5));
  CHECK(s.depth.at<float>(0, 1) == 0.0f);

  f.rgb = msgs::Image::Allocate(msgs::pb::MONO8, 2, 1);
  CHECK_THROWS_AS(ToSample(f), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::convert
