/// @file pose_test.cc
/// @brief Pose and CameraInfo messages <-> scene types round trip.
#include "convert/pose.h"

#include <cmath>

#include <catch2/catch.hpp>

#include "convert/camera_info.h"

namespace p2i::convert {
namespace {

TEST_CASE("A scene pose survives ToMsg / FromMsg, in TUM order", "[unit]") {
  const scene::Pose pose(Eigen::Vector3d(1.0, -2.0, 0.5),
                         Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY())));
  msgs::pb::Pose m;
  ToMsg(pose, &m, "map", "cam0");
  CHECK(m.parent_frame() == "map");
  CHECK(m.child_frame() == "cam0");
  const auto v = PoseVector(m);
  CHECK(v[0] == 1.0);
  CHECK(v[1] == -2.0);
  CHECK(v[2] == 0.5);
  CHECK(v[4] == Approx(std::sin(0.35)));  // qy
  CHECK(v[6] == Approx(std::cos(0.35)));  // qw last
  CHECK(FromMsg(m).equals(pose, 1e-12));

  msgs::pb::Pose n;
  SetPose({0, 0, 0, 0, 0, 0, 1}, &n);
  CHECK(FromMsg(n).equals(scene::Pose(), 1e-12));
}

TEST_CASE("CameraInfo survives ToMsg / FromMsg", "[unit]") {
  scene::CameraInfo c = scene::CameraInfo::Pinhole(640, 480, 525, 520, 319.5, 239.5, "kinect");
  c.distortion_coefficients = {0.1, -0.2, 0.0, 0.0, 0.01};
  msgs::pb::CameraInfo m;
  ToMsg(c, &m);
  CHECK(m.k_size() == 9);
  CHECK(m.p_size() == 12);
  const scene::CameraInfo back = FromMsg(m);
  CHECK(back.image_width == 640);
  CHECK(back.image_height == 480);
  CHECK(back.camera_name == "kinect");
  CHECK(back.distortion_model == "plumb_bob");
  CHECK(back.distortion_coefficients == c.distortion_coefficients);
  CHECK(back.camera_matrix == c.camera_matrix);
  CHECK(back.fy() == 520);
  CHECK(back.projection_matrix == c.projection_matrix);
  CHECK(back.rectification_matrix == c.rectification_matrix);
}

}  // namespace
}  // namespace p2i::convert
