/// @file replay_source.h
/// @brief backend:=replay: a dataset folder (p2i capture, TUM RGB-D, 7-Scenes) played at its
/// recorded stamps (x rate_scale) or a fixed rate, frames read from disk when due.
#pragma once

#include <chrono>

#include "nodes/camera/camera_options.h"
#include "nodes/camera/frame_source.h"
#include "scene/dataset_index.h"

namespace p2i::nodes {

/// When the node falls behind, the newest due frame goes out and the ones jumped over are
/// counted (frames_skipped). Counters: frames_skipped, laps. Thread-safety: FrameSource's.
class ReplaySource : public FrameSource {
 public:
  /// Opens the dataset; throws runtime::StartupError naming the folder and the problem.
  /// `options` must have passed Validate().
  explicit ReplaySource(const ReplaySourceOptions& options);

  const scene::CameraInfo& camera() const override { return camera_; }
  void Start(runtime::Node& node, Emit emit) override;

 private:
  void OnTick();
  /// Seconds after the lap start at which frame `i` is due.
  double DueTime(size_t i) const;

  ReplaySourceOptions options_;
  scene::DatasetIndex dataset_;
  scene::CameraInfo camera_;
  runtime::Node* node_ = nullptr;
  Emit emit_;
  size_t next_frame_ = 0;
  std::chrono::steady_clock::time_point lap_start_;
  bool finished_ = false;
};

}  // namespace p2i::nodes
