/// @file camera_node.h
/// @brief The camera node: RGB-D frames with intrinsics and poses from a backend chosen by
/// parameter: `sim` (the synthetic scene), `replay` (a dataset folder), or a live device:
/// `aravis` (GigE Vision / USB3 Vision) or `libcamera`.
#pragma once

#include <memory>

#include "nodes/camera/camera_options.h"
#include "nodes/camera/frame_source.h"
#include "nodes/runtime/node.h"

namespace p2i::nodes {

/// Wires CameraOptions -> a FrameSource -> the publishers. Parameters: CameraOptions
/// (camera_options.h; README.md beside this file and docs/CAMERA.md list them):
///   backend: "sim" (SimSource) | "replay" (ReplaySource) | "aravis" | "libcamera" (LiveSource);
///   frame_id ("camera"); the selected backend's own parameters.
/// Topics: publishes "rgbd" (RgbdFrame with the full camera_info and the pose) and
/// "camera_info" (CameraInfo, latched); sim in topic mode and live backends subscribe "pose"
/// (PoseStamped).
/// Counters: frames_published, and each source's own (frames_skipped, laps, frames_captured,
/// frames_dropped_no_pose, ...: see the sources' headers).
/// Thread-safety: everything runs on the node's executor thread, except a live backend's worker
/// thread (LiveSource).
class CameraNode : public runtime::Node {
 public:
  explicit CameraNode(const runtime::NodeArgs& args);

 private:
  void OnShutdown() override;
  void Publish(const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose* pose,
               int64_t capture_stamp_ns);

  std::string frame_id_;
  std::unique_ptr<FrameSource> source_;
  std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>> rgbd_pub_;
  std::shared_ptr<runtime::Publisher<msgs::pb::CameraInfo>> info_pub_;
};

}  // namespace p2i::nodes
