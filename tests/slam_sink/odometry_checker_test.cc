/// @file odometry_checker_test.cc
/// @brief OdometryChecker with the sim renderer (exact depth and ground truth).
#include "nodes/slam_sink/odometry_checker.h"

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "tests/slam_sink/sink_test_util.h"

namespace p2i::slam_sink {
namespace {

using testing::BasePose;
using testing::GarbageFrame;
using testing::Moved;
using testing::RenderedFrame;
using testing::SmallCamera;
using Status = CheckResult::Status;

TEST_CASE("OpenCV odometry Rt maps source-frame points to destination-frame points", "[unit]") {
  // The convention the checker relies on: compute(src, dst) returns Rt = T_dst^-1 * T_src for
  // camera-to-world poses T (OpenCV camera frame).
  const scene::CameraInfo camera = SmallCamera();
  const scene::Pose src_pose = BasePose();
  const scene::Pose dst_pose = Moved(src_pose, 0.04, 0.0, 0.0, 1.0);
  const SinkFrame src = RenderedFrame(src_pose, 0.0, 0, camera);
  const SinkFrame dst = RenderedFrame(dst_pose, 0.1, 1, camera);
  cv::Mat src_gray, dst_gray;
  cv::cvtColor(src.rgb, src_gray, cv::COLOR_RGB2GRAY);
  cv::cvtColor(dst.rgb, dst_gray, cv::COLOR_RGB2GRAY);
  const cv::Mat k = (cv::Mat_<float>(3, 3) << camera.fx(), 0, camera.cx(), 0, camera.fy(),
                     camera.cy(), 0, 0, 1);
  cv::rgbd::RgbdICPOdometry odometry(k);
  odometry.setMaxDepth(8.0);
  cv::Mat rt;
  REQUIRE(odometry.compute(src_gray, src.depth, cv::Mat(), dst_gray, dst.depth, cv::Mat(), rt));
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = rt.at<double>(r, c);
  }
  const scene::Pose estimated = scene::Pose::FromMatrix(m);
  const scene::Pose documented = dst_pose.Inverse() * src_pose;
  const scene::Pose inverse = src_pose.Inverse() * dst_pose;
  CHECK(scene::Pose::TranslationDistance(estimated, documented) < 0.005);
  CHECK(scene::Pose::RotationDistanceDeg(estimated, documented) < 0.3);
  CHECK(scene::Pose::TranslationDistance(estimated, inverse) > 0.05);
}

TEST_CASE("OdometryChecker passes consecutive consistent frames with mm accuracy", "[unit]") {
  OdometryChecker checker({}, SmallCamera());
  const scene::Pose a = BasePose();
  const scene::Pose b = Moved(a, 0.03, -0.01, 0.02, 1.5);
  const SinkFrame fa = RenderedFrame(a, 0.0, 0);
  const SinkFrame fb = RenderedFrame(b, 0.1, 1);
  const CheckResult first = checker.Check(fa.rgb, fa.depth, fa.pose, fa.coverage);
  CHECK(first.status == Status::kUnchecked);  // no predecessor
  const CheckResult second = checker.Check(fb.rgb, fb.depth, fb.pose, fb.coverage);
  INFO(second.reason << " t_err " << second.translation_error_m << " r_err "
                     << second.rotation_error_deg);
  CHECK(second.status == Status::kPass);
  REQUIRE(second.estimated_motion.has_value());
  CHECK(second.translation_error_m < 0.005);
  CHECK(second.rotation_error_deg < 0.3);
  // The expected motion is the pose of b in a's camera frame.
  CHECK(second.expected_motion->equals(a.Inverse() * b, 1e-9));
  CHECK(checker.stats().checked == 1);
  CHECK(checker.stats().passed == 1);
  CHECK(checker.stats().unchecked == 1);
}

TEST_CASE("OdometryChecker fails a frame whose requested pose is 10 cm off", "[unit]") {
  OdometryChecker checker({}, SmallCamera());
  const scene::Pose a = BasePose();
  const scene::Pose true_b = Moved(a, 0.02, 0.0, 0.01, 1.0);
  const SinkFrame fa = RenderedFrame(a, 0.0, 0);
  SinkFrame fb = RenderedFrame(true_b, 0.1, 1);
  fb.pose = Moved(true_b, 0.10, 0.0, 0.0);  // the view shows true_b, claims 10 cm to the right
  checker.Check(fa.rgb, fa.depth, fa.pose);
  const CheckResult r = checker.Check(fb.rgb, fb.depth, fb.pose);
  INFO(r.reason);
  CHECK(r.status == Status::kFail);
  REQUIRE(r.estimated_motion.has_value());
  CHECK(r.translation_error_m == Approx(0.10).margin(0.01));
  CHECK(checker.stats().failed_motion == 1);

  // The same view with its true pose passes (the reference is still frame a).
  const CheckResult ok = checker.Check(fb.rgb, fb.depth, true_b);
  INFO(ok.reason);
  CHECK(ok.status == Status::kPass);
}

TEST_CASE("OdometryChecker fails blank and garbage frames and recovers after them", "[unit]") {
  OdometryChecker checker({}, SmallCamera());
  const scene::Pose a = BasePose();
  const SinkFrame fa = RenderedFrame(a, 0.0, 0);
  checker.Check(fa.rgb, fa.depth, fa.pose);

  const scene::Pose b = Moved(a, 0.02, 0.0, 0.0, 0.5);
  const cv::Mat blank_rgb(fa.rgb.size(), CV_8UC3, cv::Scalar::all(0));
  const cv::Mat blank_depth(fa.depth.size(), CV_32FC1, cv::Scalar(0));
  const CheckResult blank = checker.Check(blank_rgb, blank_depth, b);
  CHECK(blank.status == Status::kFail);
  CHECK(checker.stats().failed_depth == 1);

  const SinkFrame garbage = GarbageFrame(b, 0.1, 1);
  const CheckResult g = checker.Check(garbage.rgb, garbage.depth, garbage.pose);
  INFO(g.reason << " t_err " << g.translation_error_m);
  CHECK(g.status == Status::kFail);

  // A good frame after them passes against the last good reference.
  const SinkFrame fc = RenderedFrame(Moved(a, 0.03, 0.0, 0.0, 1.0), 0.2, 2);
  const CheckResult c = checker.Check(fc.rgb, fc.depth, fc.pose);
  INFO(c.reason);
  CHECK(c.status == Status::kPass);

  // Wrong image type is a failure, not an exception.
  const CheckResult wrong = checker.Check(cv::Mat(fa.rgb.size(), CV_8UC1), fa.depth, a);
  CHECK(wrong.status == Status::kFail);
  CHECK(checker.stats().failed == 3);
  CHECK(checker.stats().pass_rate() == Approx(1.0 / 4.0));
}

TEST_CASE("OdometryChecker fails frames with a coverage score below the threshold", "[unit]") {
  OdometryCheckerOptions options;
  options.min_coverage = 0.5;
  OdometryChecker checker(options, SmallCamera());
  const SinkFrame fa = RenderedFrame(BasePose(), 0.0, 0);
  const CheckResult low = checker.Check(fa.rgb, fa.depth, fa.pose, 0.2);
  CHECK(low.status == Status::kFail);
  CHECK(checker.stats().failed_coverage == 1);
  const CheckResult unknown = checker.Check(fa.rgb, fa.depth, fa.pose);  // NaN: not reported
  CHECK(unknown.status != Status::kFail);
}

TEST_CASE("OdometryChecker over a smooth path: all pass, error statistics reported", "[unit]") {
  OdometryChecker checker({}, SmallCamera());
  const scene::Pose a = BasePose();
  for (int i = 0; i < 6; ++i) {
    const SinkFrame f = RenderedFrame(Moved(a, 0.015 * i, 0.005 * i, 0.0, 0.4 * i), 0.1 * i, i);
    const CheckResult r = checker.Check(f.rgb, f.depth, f.pose, 0.95);
    INFO(i << ": " << r.reason);
    CHECK(r.status == (i == 0 ? Status::kUnchecked : Status::kPass));
  }
  const CheckerStats& s = checker.stats();
  CHECK(s.checked == 5);
  CHECK(s.pass_rate() == 1.0);
  CHECK(s.translation_error_m.count == 5);
  CHECK(s.translation_error_m.median < 0.005);
  CHECK(s.translation_error_m.p90 >= s.translation_error_m.median);
  CHECK(s.rotation_error_deg.p90 < 0.5);

  // A jump beyond the baseline cannot be verified: unchecked, and it becomes the reference.
  const SinkFrame far = RenderedFrame(Moved(a, 0.6, 0.0, 0.0), 1.0, 7);
  CHECK(checker.Check(far.rgb, far.depth, far.pose).status == Status::kUnchecked);
}

TEST_CASE("OdometryChecker scales the intrinsics to the frame size", "[unit]") {
  // Calibration given at 320x240, frames rendered at 160x120.
  OdometryChecker checker({}, SmallCamera(320, 240));
  const scene::Pose a = BasePose();
  const scene::Pose b = Moved(a, 0.03, 0.0, 0.0, 1.0);
  const SinkFrame fa = RenderedFrame(a, 0.0, 0, SmallCamera(160, 120));
  const SinkFrame fb = RenderedFrame(b, 0.1, 1, SmallCamera(160, 120));
  checker.Check(fa.rgb, fa.depth, fa.pose);
  const CheckResult r = checker.Check(fb.rgb, fb.depth, fb.pose);
  INFO(r.reason << " " << r.translation_error_m);
  CHECK(r.status == Status::kPass);
}

TEST_CASE("ErrorSummary quantiles and OdometryChecker options validation", "[unit]") {
  const ErrorSummary s = ErrorSummary::Of({5, 1, 4, 2, 3, NAN});
  CHECK(s.count == 5);
  CHECK(s.median == Approx(3.0));
  CHECK(s.p90 == Approx(4.6));
  CHECK(s.max == Approx(5.0));
  CHECK(s.mean == Approx(3.0));
  OdometryCheckerOptions bad;
  bad.method = "orb";
  CHECK_THROWS_WITH(bad.Validate(), Catch::Contains("method"));
  CHECK_THROWS_AS(OdometryChecker({}, scene::CameraInfo{}), std::invalid_argument);
}

}  // namespace
}  // namespace p2i::slam_sink
