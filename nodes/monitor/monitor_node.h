/// @file monitor_node.h
/// @brief p2i_monitor: watches a running pipeline and prints what it achieved.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "model/lpips.h"
#include "nodes/runtime/node.h"
#include "scene/camera_info.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

/// Scores every synthesized view against the sim scene's exact ground truth at the view's pose
/// (PSNR, SSIM, LPIPS-Squeeze when the weights are found, depth AbsRel), counts captured frames,
/// published and served model versions, view latency, and after `duration` seconds prints a
/// summary (also written as JSON) and stops, so a launch file can mark it `required` to bound a
/// run. The ground truth is rendered with the sim camera and centre-cropped/resized to each
/// view's size: the same path the training frames take.
///
/// Beside the served views it scores the two free baselines on the same poses, so the summary
/// shows what P2I-NET has to beat: the nearest keyframe and the depth warp (4 nearest keyframes,
/// holes filled), whose keyframes are the frames captured so far (their poses, from `rgbd`,
/// rendered exactly by the sim scene at the view's size, i.e. what the sim camera delivered and
/// the trainer trained on; pose distance |dt| + 0.5 m per radian).
/// Thread-compatible: everything runs on the node's executor thread.
class MonitorNode : public runtime::Node {
 public:
  explicit MonitorNode(const runtime::NodeArgs& args);

 protected:
  void OnShutdown() override;

 private:
  void OnView(const msgs::View& view);
  /// Nearest-keyframe and depth-warp RGB PSNR at `pose` for a view of `truth`'s size.
  void ScoreBaselines(const scene::Pose& pose, const scene::RgbdSample& truth);
  /// The sim frame at keyframe i, at w x h (cached for the last size asked).
  const scene::RgbdSample& Keyframe(size_t i, int w, int h);
  void Finish();
  std::string SummaryText() const;

  std::optional<scene::SimScene> sim_;
  scene::CameraInfo sim_camera_;
  std::unique_ptr<model::LpipsSqueeze> lpips_;
  std::string lpips_status_;
  std::string summary_file_;
  std::string sink_summary_file_;
  std::string sequence_dir_;
  double duration_s_ = 0.0;
  int score_every_ = 1;
  std::chrono::steady_clock::time_point start_;
  bool finished_ = false;

  uint64_t frames_captured_ = 0;
  uint64_t views_received_ = 0;
  uint64_t views_scored_ = 0;
  std::set<uint64_t> versions_published_;
  std::set<uint64_t> versions_served_;
  std::vector<double> psnr_, ssim_, lpips_values_, depth_absrel_, latency_ms_, render_ms_;
  std::vector<double> coverage_;
  std::vector<scene::Pose> keyframe_poses_;
  std::map<size_t, scene::RgbdSample> keyframe_cache_;
  int keyframe_w_ = 0, keyframe_h_ = 0;
  std::vector<double> nearest_psnr_, warp_psnr_;
  std::shared_ptr<runtime::RawSubscriber> views_sub_, frames_sub_, versions_sub_;
};

}  // namespace p2i::nodes
