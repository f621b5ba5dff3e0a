/// @file odometry_checker.cc
/// @brief OdometryChecker: OpenCV RGB-D odometry against the requested relative motion.
#include "nodes/slam_sink/odometry_checker.h"

#include <cmath>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

namespace p2i::slam_sink {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

scene::Pose PoseFromRt(const cv::Mat& rt) {
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = rt.at<double>(r, c);
  }
  return scene::Pose::FromMatrix(m);
}

}  // namespace

const char* CheckResult::StatusName() const {
  switch (status) {
    case Status::kPass:
      return "pass";
    case Status::kFail:
      return "fail";
    case Status::kUnchecked:
      return "unchecked";
  }
  return "unchecked";
}

void OdometryCheckerOptions::Validate() const {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("OdometryCheckerOptions: " + what);
  };
  require(method == "rgbd_icp" || method == "icp" || method == "rgbd",
          "method must be rgbd_icp, icp or rgbd, got '" + method + "'");
  require(max_translation_error_m > 0.0, "max_translation_error_m must be > 0");
  require(max_rotation_error_deg > 0.0, "max_rotation_error_deg must be > 0");
  require(min_coverage >= 0.0 && min_coverage <= 1.0, "min_coverage must be in [0, 1]");
  require(min_valid_depth_fraction >= 0.0 && min_valid_depth_fraction <= 1.0,
          "min_valid_depth_fraction must be in [0, 1]");
  require(min_depth_m >= 0.0 && max_depth_m > min_depth_m,
          "need 0 <= min_depth_m < max_depth_m");
  require(max_baseline_m > 0.0 && max_baseline_deg > 0.0,
          "max_baseline_m and max_baseline_deg must be > 0");
}

OdometryChecker::OdometryChecker(OdometryCheckerOptions options, const scene::CameraInfo& camera)
    : options_(std::move(options)), camera_(camera) {
  options_.Validate();
  if (!(camera_.fx() > 0.0 && camera_.fy() > 0.0 && camera_.image_width > 0 &&
        camera_.image_height > 0)) {
    throw std::invalid_argument("OdometryChecker: camera '" + camera_.camera_name +
                                "' needs a positive size and focal lengths (check the "
                                "camera_info file)");
  }
}

OdometryChecker::~OdometryChecker() = default;

cv::Mat OdometryChecker::CameraMatrixFor(cv::Size size) const {
  const double sx = static_cast<double>(size.width) / camera_.image_width;
  const double sy = static_cast<double>(size.height) / camera_.image_height;
  // Pixel centres stay centres under scaling: (c + 0.5) * s - 0.5.
  return (cv::Mat_<float>(3, 3) << camera_.fx() * sx, 0, (camera_.cx() + 0.5) * sx - 0.5, 0,
          camera_.fy() * sy, (camera_.cy() + 0.5) * sy - 0.5, 0, 0, 1);
}

void OdometryChecker::MotionError(const scene::Pose& estimated, const scene::Pose& expected,
                                  double* translation_error_m, double* rotation_error_deg) {
  *translation_error_m = (estimated.translation() - expected.translation()).norm();
  *rotation_error_deg = scene::Pose::RotationDistanceDeg(estimated, expected);
}

cv::Ptr<cv::rgbd::Odometry> OdometryChecker::OdometryFor(cv::Size size) {
  if (odometry_ && odometry_size_ == size) return odometry_;
  const cv::Mat k = CameraMatrixFor(size);
  // OpenCV's own plausibility limits (default 0.15 m / 15 deg) must not reject motions we
  // still want to measure.
  const double max_translation = 2.0 * options_.max_baseline_m + 0.5;
  const double max_rotation = 2.0 * options_.max_baseline_deg + 15.0;
  if (options_.method == "rgbd") {
    auto o = cv::makePtr<cv::rgbd::RgbdOdometry>(k);
    o->setMinDepth(options_.min_depth_m);
    o->setMaxDepth(options_.max_depth_m);
    o->setMaxTranslation(max_translation);
    o->setMaxRotation(max_rotation);
    odometry_ = o;
  } else if (options_.method == "icp") {
    auto o = cv::makePtr<cv::rgbd::ICPOdometry>(k);
    o->setMinDepth(options_.min_depth_m);
    o->setMaxDepth(options_.max_depth_m);
    o->setMaxTranslation(max_translation);
    o->setMaxRotation(max_rotation);
    odometry_ = o;
  } else {
    auto o = cv::makePtr<cv::rgbd::RgbdICPOdometry>(k);
    o->setMinDepth(options_.min_depth_m);
    o->setMaxDepth(options_.max_depth_m);
    o->setMaxTranslation(max_translation);
    o->setMaxRotation(max_rotation);
    odometry_ = o;
  }
  odometry_size_ = size;
  return odometry_;
}

bool OdometryChecker::Estimate(const Frame& reference, const Frame& frame,
                               scene::Pose* motion) const {
  if (!odometry_ || !frame.cache || !reference.cache) return false;
  cv::Ptr<cv::rgbd::OdometryFrame> src = frame.cache, dst = reference.cache;
  cv::Mat rt;
  bool ok = false;
  try {
    // src = new frame, dst = reference: Rt = T_ref^-1 * T_new (see the class comment).
    ok = odometry_->compute(src, dst, rt);
  } catch (const cv::Exception&) {
    ok = false;  // degenerate input (e.g. no valid pixels on a pyramid level)
  }
  if (!ok || rt.empty() || !cv::checkRange(rt)) return false;
  *motion = PoseFromRt(rt);
  return true;
}

CheckResult OdometryChecker::CompareWith(const Frame& reference, const Frame& frame) const {
  CheckResult result;
  const scene::Pose expected = reference.pose.Inverse() * frame.pose;
  result.expected_motion = expected;
  scene::Pose estimated;
  if (!Estimate(reference, frame, &estimated)) {
    result.status = CheckResult::Status::kFail;
    result.reason = "odometry found no solution";
    return result;
  }
  result.estimated_motion = estimated;
  MotionError(estimated, expected, &result.translation_error_m, &result.rotation_error_deg);
  if (result.translation_error_m > options_.max_translation_error_m ||
      result.rotation_error_deg > options_.max_rotation_error_deg) {
    result.status = CheckResult::Status::kFail;
    result.reason = "motion disagrees with the requested poses";
  } else {
    result.status = CheckResult::Status::kPass;
  }
  return result;
}

void OdometryChecker::Record(const CheckResult& result) {
  switch (result.status) {
    case CheckResult::Status::kPass:
      ++stats_.checked;
      ++stats_.passed;
      break;
    case CheckResult::Status::kFail:
      ++stats_.checked;
      ++stats_.failed;
      break;
    case CheckResult::Status::kUnchecked:
      ++stats_.unchecked;
      break;
  }
  if (result.estimated_motion) {
    translation_errors_.push_back(result.translation_error_m);
    rotation_errors_.push_back(result.rotation_error_deg);
    stats_.translation_error_m = ErrorSummary::Of(translation_errors_);
    stats_.rotation_error_deg = ErrorSummary::Of(rotation_errors_);
  }
}

CheckResult OdometryChecker::Check(const cv::Mat& rgb, const cv::Mat& depth,
                                   const scene::Pose& requested, double coverage) {
  CheckResult result;
  if (std::isfinite(coverage) && coverage < options_.min_coverage) {
    result.status = CheckResult::Status::kFail;
    result.reason = "coverage below min_coverage";
    ++stats_.failed_coverage;
    Record(result);
    return result;
  }
  if (rgb.empty() || rgb.type() != CV_8UC3 || depth.type() != CV_32FC1 ||
      depth.size() != rgb.size() || rgb.rows < 16 || rgb.cols < 16) {
    result.status = CheckResult::Status::kFail;
    result.reason = "rgb must be CV_8UC3 and depth CV_32FC1 of the same size (>= 16x16)";
    ++stats_.failed_depth;
    Record(result);
    return result;
  }
  auto frame = std::make_shared<Frame>();
  cv::cvtColor(rgb, frame->gray, cv::COLOR_RGB2GRAY);
  frame->depth = depth.clone();
  cv::patchNaNs(frame->depth, 0.0);
  frame->mask = (frame->depth > options_.min_depth_m) & (frame->depth < options_.max_depth_m);
  frame->pose = requested;
  if (reference_ && reference_->gray.size() != frame->gray.size()) {
    reference_.reset();  // a new image size starts a new chain of references
    previous_.reset();
  }
  const double valid_fraction =
      static_cast<double>(cv::countNonZero(frame->mask)) / (frame->mask.total());
  if (valid_fraction < options_.min_valid_depth_fraction) {
    result.status = CheckResult::Status::kFail;
    result.reason = "too few valid depth pixels";
    ++stats_.failed_depth;
    Record(result);
    return result;  // an insane frame is never a reference
  }

  try {
    const cv::Ptr<cv::rgbd::Odometry> odometry = OdometryFor(frame->gray.size());
    frame->cache = cv::makePtr<cv::rgbd::OdometryFrame>(frame->gray, frame->depth, frame->mask);
    odometry->prepareFrameCache(frame->cache, cv::rgbd::OdometryFrame::CACHE_ALL);
  } catch (const cv::Exception&) {
    frame->cache.release();  // Estimate() then reports "no solution"
  }

  auto far_from = [&](const Frame& ref) {
    return scene::Pose::TranslationDistance(ref.pose, requested) > options_.max_baseline_m ||
           scene::Pose::RotationDistanceDeg(ref.pose, requested) > options_.max_baseline_deg;
  };
  if (!reference_ || far_from(*reference_)) {
    result.status = CheckResult::Status::kUnchecked;
    result.reason = reference_ ? "baseline to the reference too large" : "no reference yet";
    reference_ = frame;
    previous_ = frame;
    Record(result);
    return result;
  }
  result = CompareWith(*reference_, *frame);
  if (!result.passed() && previous_ && previous_ != reference_ && !far_from(*previous_)) {
    CheckResult retry = CompareWith(*previous_, *frame);
    if (retry.passed()) result = retry;
  }
  if (result.passed()) {
    reference_ = frame;
  } else if (!result.estimated_motion) {
    ++stats_.failed_odometry;
  } else {
    ++stats_.failed_motion;
  }
  previous_ = frame;
  Record(result);
  return result;
}

}  // namespace p2i::slam_sink
