/// @file baseline_nearest_test.cc
/// @brief Nearest-keyframe baseline: exact frame for a training pose, right neighbour in between,
/// and the rotation weight of the pose distance.
#include <cmath>

#include <catch2/catch.hpp>

#include "model/baseline_nearest.h"

using namespace p2i::model;
using p2i::scene::Pose;

namespace {

Pose At(double x, double yaw_deg) {
  return Pose(Eigen::Vector3d(x, 0.0, 0.0),
              Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY())));
}

/// Three frames at x = 0, 1, 2; the third rotated 10 degrees. Each frame has a distinct colour.
p2i::scene::RgbdDataset Dataset() {
  p2i::scene::RgbdDataset d;
  d.camera = p2i::scene::CameraInfo::Pinhole(8, 6, 10, 10, 3.5, 2.5);
  const double yaws[3] = {0.0, 0.0, 10.0};
  for (int i = 0; i < 3; ++i) {
    p2i::scene::RgbdSample s;
    s.pose = At(i, yaws[i]);
    s.rgb = cv::Mat(6, 8, CV_8UC3, cv::Scalar(40 * i + 10, 200 - 30 * i, 7 * i));
    s.depth = cv::Mat(6, 8, CV_32FC1, cv::Scalar(1.0 + i));
    s.id = "f" + std::to_string(i);
    d.frames.push_back(s);
  }
  return d;
}

bool SameImage(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

}  // namespace

TEST_CASE("NearestKeyframe returns the exact frame at a training pose", "[unit]") {
  const auto data = Dataset();
  NearestKeyframe nk(data);
  for (size_t i = 0; i < data.frames.size(); ++i) {
    const p2i::scene::RgbdSample v = nk.Render(data.frames[i].pose);
    CHECK(nk.NearestIndex(data.frames[i].pose) == i);
    CHECK(SameImage(v.rgb, data.frames[i].rgb));
    CHECK(SameImage(v.depth, data.frames[i].depth));
    CHECK(v.id == "nearest:" + data.frames[i].id);
    CHECK(v.pose.equals(data.frames[i].pose));
  }
  // A deep copy: changing the returned view leaves the training frame intact.
  p2i::scene::RgbdSample v = nk.Render(data.frames[0].pose);
  v.rgb.setTo(cv::Scalar::all(0));
  CHECK(nk.Render(data.frames[0].pose).rgb.at<cv::Vec3b>(0, 0)[0] == 10);
  CHECK(nk.Camera().image_width == 8);
}

TEST_CASE("NearestKeyframe picks the right neighbour between two poses", "[unit]") {
  const auto data = Dataset();
  NearestKeyframe nk(data);
  CHECK(nk.NearestIndex(At(0.4, 0.0)) == 0);
  CHECK(nk.NearestIndex(At(0.6, 0.0)) == 1);
  CHECK(SameImage(nk.Render(At(0.6, 0.0)).rgb, data.frames[1].rgb));
  // Between frame 1 (yaw 0) and frame 2 (yaw 10) with the query at yaw 10: the rotation weight
  // decides. 0.01 m/deg: d1 = 0.4 + 0.1 < d2 = 0.6. 0.03 m/deg: d1 = 0.4 + 0.3 > d2 = 0.6.
  const Pose q = At(1.4, 10.0);
  CHECK(nk.NearestIndex(q) == 1);
  NearestKeyframeOptions heavy;
  heavy.metres_per_degree = 0.03;
  NearestKeyframe nk_rot(data, heavy);
  CHECK(nk_rot.NearestIndex(q) == 2);
  CHECK_THROWS_AS(NearestKeyframe(p2i::scene::RgbdDataset{}), std::invalid_argument);
}
