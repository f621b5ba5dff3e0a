/// @file frame_pose_matcher_test.cc
/// @brief FramePoseMatcher with a fake clock: frames matched, held for newer poses, dropped for
/// each reason and counted.
#include <catch2/catch.hpp>

#include "nodes/camera/frame_pose_matcher.h"

namespace p2i::nodes {
namespace {

constexpr int64_t kMs = 1'000'000;

LiveFrame Frame(int64_t stamp_ns, uint64_t id) {
  LiveFrame f;
  f.stamp_ns = stamp_ns;
  f.frame_id = id;
  f.rgb = cv::Mat(2, 2, CV_8UC3, cv::Scalar(static_cast<double>(id), 0, 0));
  return f;
}

scene::Pose At(double x) {
  return scene::Pose(Eigen::Vector3d(x, 0, 0), Eigen::Quaterniond::Identity());
}

FramePoseMatcher::Options Opts() {
  FramePoseMatcher::Options o;
  o.tolerance_ns = 100 * kMs;
  o.max_wait_ns = 200 * kMs;
  o.max_pending = 3;
  o.pose_capacity = 8;
  return o;
}

TEST_CASE("FramePoseMatcher gives a bracketed frame the interpolated pose", "[unit]") {
  FramePoseMatcher m(Opts());
  m.AddPose(1000 * kMs, At(1.0));
  m.AddPose(1100 * kMs, At(2.0));
  m.AddFrame(Frame(1030 * kMs, 7), 0);
  const auto out = m.Poll(0);
  REQUIRE(out.size() == 1);
  CHECK(out[0].frame.frame_id == 7);
  CHECK(out[0].frame.stamp_ns == 1030 * kMs);
  CHECK(out[0].pose.translation().x() == Approx(1.3).margin(1e-12));
  CHECK(m.counters().matched == 1);
  CHECK(m.pending() == 0);
}

TEST_CASE("FramePoseMatcher holds a frame until a newer pose arrives, within max_wait",
          "[unit]") {
  FramePoseMatcher m(Opts());
  m.AddPose(1000 * kMs, At(0.0));
  m.AddFrame(Frame(1050 * kMs, 1), 0);   // newer than the newest pose: wait
  m.AddFrame(Frame(1060 * kMs, 2), 5 * kMs);
  CHECK(m.Poll(10 * kMs).empty());
  CHECK(m.pending() == 2);
  m.AddPose(1100 * kMs, At(1.0));
  const auto out = m.Poll(20 * kMs);
  REQUIRE(out.size() == 2);  // in arrival order
  CHECK(out[0].frame.frame_id == 1);
  CHECK(out[0].pose.translation().x() == Approx(0.5).margin(1e-12));
  CHECK(out[1].frame.frame_id == 2);
  CHECK(out[1].pose.translation().x() == Approx(0.6).margin(1e-12));
  CHECK(m.counters().dropped() == 0);
}

TEST_CASE("FramePoseMatcher drops and counts frames that get no pose", "[unit]") {
  FramePoseMatcher m(Opts());
  SECTION("no pose at all within max_wait") {
    m.AddFrame(Frame(1000 * kMs, 1), 0);
    CHECK(m.Poll(199 * kMs).empty());
    CHECK(m.pending() == 1);
    CHECK(m.Poll(200 * kMs).empty());
    CHECK(m.pending() == 0);
    CHECK(m.counters().dropped_timeout == 1);
  }
  SECTION("older than every pose kept") {
    m.AddPose(1000 * kMs, At(0.0));
    m.AddPose(1100 * kMs, At(1.0));
    m.AddFrame(Frame(900 * kMs, 1), 0);
    CHECK(m.Poll(0).empty());
    CHECK(m.counters().dropped_too_old == 1);
  }
  SECTION("poses too far apart around the stamp") {
    m.AddPose(1000 * kMs, At(0.0));
    m.AddPose(1300 * kMs, At(1.0));
    m.AddFrame(Frame(1150 * kMs, 1), 0);
    CHECK(m.Poll(0).empty());
    CHECK(m.counters().dropped_gap == 1);
  }
  SECTION("more frames waiting than max_pending: the oldest goes") {
    for (uint64_t i = 1; i <= 4; ++i) m.AddFrame(Frame((1000 + 10 * i) * kMs, i), 0);
    CHECK(m.counters().dropped_overflow == 1);
    m.AddPose(1000 * kMs, At(0.0));
    m.AddPose(1100 * kMs, At(1.0));
    const auto out = m.Poll(0);
    REQUIRE(out.size() == 3);
    CHECK(out[0].frame.frame_id == 2);
    CHECK(out[2].frame.frame_id == 4);
  }
  CHECK(m.counters().dropped() == 1);
}

TEST_CASE("FramePoseMatcher counts duplicate and stale poses", "[unit]") {
  FramePoseMatcher::Options o = Opts();
  o.pose_capacity = 2;
  FramePoseMatcher m(o);
  m.AddPose(100 * kMs, At(0.0));
  m.AddPose(100 * kMs, At(0.0));
  m.AddPose(200 * kMs, At(1.0));
  m.AddPose(50 * kMs, At(1.0));
  CHECK(m.counters().poses_duplicate == 1);
  CHECK(m.counters().poses_too_old == 1);
  FramePoseMatcher::Options bad = Opts();
  bad.max_pending = 0;
  CHECK_THROWS_AS(FramePoseMatcher(bad), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::nodes
