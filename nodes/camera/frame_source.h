/// @file frame_source.h
/// @brief The interface of the camera node's backends (sim, replay, live): what each yields
/// (RGB-D frames, their capture stamps and poses, the intrinsics), and nothing of how.
#pragma once

#include <cstdint>
#include <functional>

#include <opencv2/core.hpp>

#include "nodes/runtime/node.h"
#include "scene/camera_info.h"
#include "scene/pose.h"

namespace p2i::nodes {

/// One backend of the camera node. Opening (the source's constructor) reads the scene, dataset
/// or device and fixes camera(); it throws runtime::StartupError naming the problem. Start()
/// then makes the source yield frames through `emit` on the node's executor thread, using the
/// node for its timers, the "pose" subscription, counters and logs; Stop() (from
/// CameraNode::OnShutdown) ends it, after which `emit` is not called again.
///
/// Thread-safety: Start, Stop and camera() on the node's executor thread; a source with a
/// worker thread (LiveSource) hands frames to that thread itself.
class FrameSource {
 public:
  /// rgb CV_8UC3 RGB, depth CV_32FC1 metres (0 invalid), `pose` camera-to-world or nullptr
  /// (no pose), the capture stamp (system clock, ns).
  using Emit = std::function<void(const cv::Mat& rgb, const cv::Mat& depth,
                                  const scene::Pose* pose, int64_t capture_stamp_ns)>;

  virtual ~FrameSource() = default;
  /// The intrinsics of every frame the source yields.
  virtual const scene::CameraInfo& camera() const = 0;
  /// Called once, after the node's publishers exist.
  virtual void Start(runtime::Node& node, Emit emit) = 0;
  virtual void Stop() {}
};

}  // namespace p2i::nodes
