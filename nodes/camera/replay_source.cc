/// @file replay_source.cc
/// @brief ReplaySource: dataset frames published when their (scaled) recorded time has come.
#include "nodes/camera/replay_source.h"

#include "scene/dataset_loader.h"
#include "scene/image_ops.h"

namespace p2i::nodes {

ReplaySource::ReplaySource(const ReplaySourceOptions& options) : options_(options) {
  const ReplaySourceOptions& o = options_;
  try {
    scene::DatasetOptions dataset_options;
    dataset_options.format = o.format;
    dataset_options.seven_scenes_invalid_depth = o.invalid_depth;
    dataset_options.camera_info_file = o.camera_info_file;
    dataset_ = scene::OpenDataset(o.dataset, dataset_options);
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  if (dataset_.empty()) throw runtime::StartupError("dataset '" + o.dataset + "' has no frames");
  camera_ = o.width > 0 ? scene::CenterCropResizeCamera(dataset_.camera(), o.width, o.height)
                        : dataset_.camera();
}

void ReplaySource::Start(runtime::Node& node, Emit emit) {
  node_ = &node;
  emit_ = std::move(emit);
  node.Log().info("replay backend: {} frames from '{}' at {}", dataset_.size(), options_.dataset,
                  options_.rate > 0.0
                      ? std::to_string(options_.rate) + " Hz"
                      : "the recorded rate x " + std::to_string(options_.rate_scale));
  lap_start_ = std::chrono::steady_clock::now();
  // A short tick: frames go out when their (scaled) recorded time has come.
  node.AddTimer(std::chrono::milliseconds(2), [this] { OnTick(); });
}

double ReplaySource::DueTime(size_t i) const {
  if (options_.rate > 0.0) return static_cast<double>(i) / options_.rate;
  return (dataset_.frames()[i].stamp - dataset_.frames().front().stamp) / options_.rate_scale;
}

void ReplaySource::OnTick() {
  if (finished_) return;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - lap_start_).count();
  if (DueTime(next_frame_) > elapsed) return;
  // Fell behind: publish the newest due frame, count the ones jumped over.
  size_t i = next_frame_;
  while (i + 1 < dataset_.size() && DueTime(i + 1) <= elapsed) ++i;
  if (i > next_frame_) node_->Count("frames_skipped", i - next_frame_);
  scene::RgbdSample sample = dataset_.Load(i);
  if (options_.width > 0) {
    sample = scene::CenterCropResizeSample(sample, options_.width, options_.height);
  }
  emit_(sample.rgb, sample.depth, &sample.pose, runtime::NowNs());
  next_frame_ = i + 1;
  if (next_frame_ < dataset_.size()) return;
  node_->Count("laps");
  if (options_.loop) {
    next_frame_ = 0;
    // The next lap starts one frame period (20 Hz with recorded stamps) after this last frame.
    const double period_s = 1.0 / (options_.rate > 0.0 ? options_.rate : 20.0);
    lap_start_ = std::chrono::steady_clock::now() +
                 std::chrono::nanoseconds(static_cast<int64_t>(1e9 * period_s));
  } else {
    finished_ = true;
    node_->Log().info("replay finished ({} frames)", dataset_.size());
    if (options_.exit_at_end) node_->Stop();
  }
}

}  // namespace p2i::nodes
