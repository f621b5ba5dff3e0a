/// @file camera_node.h
/// @brief The camera node: RGB-D frames with intrinsics and poses from a backend chosen by
/// parameter: `sim` (the synthetic scene), `replay` (a dataset folder), or a live device:
/// `aravis` (GigE Vision / USB3 Vision) or `libcamera`.
#pragma once

#include <chrono>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "nodes/camera/frame_pose_matcher.h"
#include "nodes/camera/live_backend.h"
#include "nodes/runtime/node.h"
#include "scene/dataset_index.h"
#include "scene/pose.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

/// Parameters (README.md beside this file has the full list):
///   backend: "sim" | "replay" | "aravis" | "libcamera";
///   rate (Hz): sim frames per second (20); replay: 0 = the recorded rate;
///   width, height (0 = native): sim render size; replay centre-crop + resize;
///   camera_info_file: ROS camera_info YAML (sim; replay: override);
///   sim: scene ("builtin:small_office" or a YAML file), kinect (bool), pose_mode ("topic":
///     render at the newest pose received on "pose", at most `rate` per second; "trajectory":
///     its own trajectory spec), trajectory, trajectory_index, loop;
///   replay: dataset (folder), format, invalid_depth (7-Scenes raw value), rate_scale (1.0),
///     loop (false), exit_at_end (false);
///   live (aravis, libcamera): camera_info_file (scaled to the stream size if the aspect
///     matches), pose_mode ("topic": each frame gets the pose interpolated at its capture stamp
///     from "pose", frames without one are dropped; "none": frames carry no pose),
///     pose_tolerance (s, 0.05), pose_wait (s, 0.2), max_pending (8), stamp_offset (s, 0:
///     subtracted from the host reception stamp);
///   aravis: device, pixel_format, width, height, frame_rate, exposure_us, depth_device,
///     depth_scale, depth_tolerance, buffers; libcamera: camera, width, height, buffers.
/// Topics: publishes "rgbd" (RgbdFrame with the full camera_info and the pose) and
/// "camera_info" (CameraInfo, latched); sim in topic mode and live backends subscribe "pose"
/// (PoseStamped).
/// Counters: frames_published, frames_skipped (replay fell behind), laps; live: frames_captured,
/// frames_dropped_no_pose (sum of frames_dropped_pose_{too_old,gap,timeout,overflow}),
/// frames_dropped_backlog, frames_incomplete, frames_without_depth.
/// Thread-safety: everything runs on the node's executor thread, except a live backend's worker
/// thread, which hands frames over through a mutex-guarded queue and Executor::Post.
class CameraNode : public runtime::Node {
 public:
  explicit CameraNode(const runtime::NodeArgs& args);

 private:
  void SetUpSim();
  void SetUpReplay();
  void SetUpLive(const std::string& backend);
  void OnShutdown() override;
  void PublishSample(const scene::RgbdSample& sample, int64_t capture_stamp_ns);
  void Publish(const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose* pose,
               int64_t capture_stamp_ns);
  void OnSimTick();
  void OnReplayTick();
  void OnLiveFrame(LiveFrame&& frame);  ///< worker thread
  void DrainLiveFrames();               ///< executor thread
  void PublishMatched();
  void SyncLiveCounters();

  std::string frame_id_;
  scene::CameraInfo camera_;
  std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>> rgbd_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::CameraInfo>> info_pub_;
  std::shared_ptr<runtime::RawSubscriber> pose_sub_;
  double rate_ = 20.0;
  bool loop_ = false;
  bool exit_at_end_ = false;

  // sim
  std::optional<scene::SimScene> sim_;
  std::vector<scene::StampedPose> trajectory_;
  size_t trajectory_index_ = 0;
  std::optional<scene::Pose> pending_pose_;  ///< newest pose from the topic, not yet rendered
  int64_t pending_stamp_ns_ = 0;

  // replay
  scene::DatasetIndex dataset_;
  int out_width_ = 0, out_height_ = 0;
  double rate_scale_ = 1.0;
  size_t next_frame_ = 0;
  std::chrono::steady_clock::time_point lap_start_;
  bool finished_ = false;

  // live (aravis, libcamera)
  std::unique_ptr<LiveBackend> live_;
  std::optional<FramePoseMatcher> matcher_;  ///< empty with pose_mode none
  int64_t stamp_offset_ns_ = 0;
  std::mutex handoff_mutex_;
  std::deque<LiveFrame> handoff_;  ///< from the worker, guarded by handoff_mutex_
  bool drain_posted_ = false;      ///< guarded by handoff_mutex_
  FramePoseMatcher::Counters reported_;
  LiveBackend::Stats reported_stats_;
};

}  // namespace p2i::nodes
