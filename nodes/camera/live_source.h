/// @file live_source.h
/// @brief backend:=aravis | libcamera: frames from a live device (LiveBackend) on its worker
/// thread, each given the pose interpolated at its capture stamp from "pose"
/// (FramePoseMatcher), or no pose with pose_mode none.
#pragma once

#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "nodes/camera/camera_options.h"
#include "nodes/camera/frame_pose_matcher.h"
#include "nodes/camera/frame_source.h"
#include "nodes/camera/live_backend.h"

namespace p2i::nodes {

/// Counters: frames_captured, frames_dropped_no_pose (sum of
/// frames_dropped_pose_{too_old,gap,timeout,overflow}), frames_dropped_backlog,
/// frames_incomplete, frames_without_depth, poses_duplicate, poses_too_old. A device failure
/// while streaming ends the node's Spin() with the device's error (exit 1).
/// Thread-safety: FrameSource's; the device's worker hands frames over through a mutex-guarded
/// queue and Executor::Post.
class LiveSource : public FrameSource {
 public:
  /// Opens `backend` ("aravis" or "libcamera") and reads the calibration; throws
  /// runtime::StartupError naming the device or file. `options` must have passed Validate().
  LiveSource(const std::string& backend, const LiveSourceOptions& options);
  ~LiveSource() override;

  const scene::CameraInfo& camera() const override { return camera_; }
  /// Subscribes "pose" (pose_mode topic), then starts streaming.
  void Start(runtime::Node& node, Emit emit) override;
  void Stop() override;

 private:
  /// camera_info_file scaled to the stream size, or the nominal pinhole ("").
  void OpenCalibration();
  void OnFrame(LiveFrame&& frame);  ///< worker thread
  void Drain();                     ///< executor thread
  void PublishMatched();
  void SyncCounters();
  void WarnDropped(const FramePoseMatcher::Counters& now);

  std::string backend_name_;
  LiveSourceOptions options_;
  std::unique_ptr<LiveBackend> device_;
  scene::CameraInfo camera_;
  bool nominal_camera_ = false;  ///< no camera_info_file: warned about at Start()
  runtime::Node* node_ = nullptr;
  Emit emit_;
  std::shared_ptr<runtime::RawSubscriber> pose_sub_;
  std::optional<FramePoseMatcher> matcher_;  ///< empty with pose_mode none
  int64_t stamp_offset_ns_ = 0;
  std::mutex handoff_mutex_;
  std::deque<LiveFrame> handoff_;  ///< from the worker, guarded by handoff_mutex_
  bool drain_posted_ = false;      ///< guarded by handoff_mutex_
  FramePoseMatcher::Counters reported_;
  LiveBackend::Stats reported_stats_;
};

}  // namespace p2i::nodes
