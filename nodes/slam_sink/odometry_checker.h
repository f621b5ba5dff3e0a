/// @file odometry_checker.h
/// @brief Checks synthetic RGB-D frames for geometric consistency with OpenCV's RGB-D odometry.
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/rgbd.hpp>

#include "nodes/slam_sink/error_stats.h"
#include "scene/camera_info.h"
#include "scene/pose.h"

namespace p2i::slam_sink {

struct OdometryCheckerOptions {
  /// OpenCV odometry: "rgbd_icp" (cv::rgbd::RgbdICPOdometry, photometric + geometric), "icp"
  /// (cv::rgbd::ICPOdometry, depth only) or "rgbd" (cv::rgbd::RgbdOdometry, photometric).
  std::string method = "rgbd_icp";
  double max_translation_error_m = 0.02;  ///< |t_est - t_expected| above this fails
  double max_rotation_error_deg = 1.0;    ///< angle(R_est^T R_expected) above this fails
  /// Frames whose reported coverage score is below this fail (NaN coverage = not reported: skip).
  double min_coverage = 0.3;
  /// Frames with fewer valid depth pixels (within [min_depth, max_depth]) than this fail.
  double min_valid_depth_fraction = 0.2;
  double min_depth_m = 0.1;
  double max_depth_m = 8.0;
  /// Odometry only converges for small motions: a frame farther than this from its reference is
  /// not verified ("unchecked") and becomes the new reference.
  double max_baseline_m = 0.3;
  double max_baseline_deg = 15.0;

  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// The outcome of checking one frame.
struct CheckResult {
  enum class Status { kPass, kFail, kUnchecked };
  Status status = Status::kUnchecked;
  std::string reason;  ///< why it failed / was not checked; empty on pass
  double translation_error_m = std::numeric_limits<double>::quiet_NaN();
  double rotation_error_deg = std::numeric_limits<double>::quiet_NaN();
  /// When odometry ran: its estimate and the motion the requested poses imply, both as the pose
  /// of the new frame in the reference frame's camera frame (T_ref^-1 * T_new).
  std::optional<scene::Pose> estimated_motion;
  std::optional<scene::Pose> expected_motion;

  bool passed() const { return status == Status::kPass; }
  const char* StatusName() const;
};

/// Counters and error statistics over all Check() calls.
struct CheckerStats {
  size_t checked = 0;  ///< frames compared with odometry or failed by a sanity test
  size_t passed = 0;
  size_t failed = 0;
  size_t unchecked = 0;  ///< first frame, too large a baseline
  size_t failed_coverage = 0;
  size_t failed_depth = 0;
  size_t failed_odometry = 0;  ///< OpenCV found no solution
  size_t failed_motion = 0;    ///< solution disagrees with the requested poses
  ErrorSummary translation_error_m;  ///< over frames where odometry produced an estimate
  ErrorSummary rotation_error_deg;
  double pass_rate() const { return checked == 0 ? 0.0 : static_cast<double>(passed) / checked; }
};

/// Checks each frame against a reference with OpenCV RGB-D odometry: it estimates the relative
/// motion from the images and compares it with the relative motion of the requested poses.
///
/// Conventions. Requested poses are camera-to-world with the OpenCV camera frame (x right, y
/// down, z forward). cv::rgbd::Odometry::compute(src, dst) returns Rt with dst_p = Rt * src_p
/// (verified by odometry_checker_test), i.e. Rt = T_dst^-1 * T_src. We call it with src = the new
/// frame and dst = the reference, so Rt = T_ref^-1 * T_new: the pose of the new frame in the
/// reference's camera frame, the same quantity as `expected_motion`.
///
/// Reference: the last frame that passed (or the first sane frame, or the first beyond the
/// baseline). If the frame fails against it and the immediate predecessor is a different sane
/// frame, the frame is also tried against the predecessor and passes if that agrees (so one bad
/// reference cannot make every later frame fail).
///
/// Thread-compatible: one thread calls Check().
class OdometryChecker {
 public:
  /// `camera` gives the intrinsics at its own resolution; frames of another size use them scaled
  /// per axis. Throws std::invalid_argument on invalid options or a camera without focal lengths.
  OdometryChecker(OdometryCheckerOptions options, const scene::CameraInfo& camera);
  ~OdometryChecker();

  /// rgb CV_8UC3 (RGB order), depth CV_32FC1 metres (0 invalid), `requested` camera-to-world,
  /// `coverage` NaN when unknown. Never throws on bad image content (a wrong type fails).
  CheckResult Check(const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose& requested,
                    double coverage = std::numeric_limits<double>::quiet_NaN());

  const CheckerStats& stats() const { return stats_; }
  const OdometryCheckerOptions& options() const { return options_; }

  /// Relative motion errors between two poses: translation (m) and rotation angle (deg).
  static void MotionError(const scene::Pose& estimated, const scene::Pose& expected,
                          double* translation_error_m, double* rotation_error_deg);

 private:
  struct Frame {
    cv::Mat gray;
    cv::Mat depth;
    cv::Mat mask;
    scene::Pose pose;
    // Pyramids and normals computed once (CACHE_ALL: usable as source now and as reference
    // later); null when OpenCV rejected the frame's data.
    cv::Ptr<cv::rgbd::OdometryFrame> cache;
  };
  // Runs odometry new -> reference; false when OpenCV finds no solution.
  bool Estimate(const Frame& reference, const Frame& frame, scene::Pose* motion) const;
  CheckResult CompareWith(const Frame& reference, const Frame& frame) const;
  cv::Mat CameraMatrixFor(cv::Size size) const;
  // The odometry object for frames of `size`, created on first use (its normals computer and
  // internal buffers are expensive to set up, so it is kept while the size stays the same).
  cv::Ptr<cv::rgbd::Odometry> OdometryFor(cv::Size size);
  void Record(const CheckResult& result);

  OdometryCheckerOptions options_;
  scene::CameraInfo camera_;
  std::shared_ptr<Frame> reference_;
  std::shared_ptr<Frame> previous_;  // the immediate predecessor if it was sane
  cv::Ptr<cv::rgbd::Odometry> odometry_;
  cv::Size odometry_size_;
  CheckerStats stats_;
  std::vector<double> translation_errors_;
  std::vector<double> rotation_errors_;
};

}  // namespace p2i::slam_sink
