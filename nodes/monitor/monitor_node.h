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
#include "nodes/monitor/keyframe_baselines.h"
#include "nodes/monitor/monitor_options.h"
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
/// Beside the served views it scores the two free baselines on the same poses (PSNR, SSIM), so
/// the summary shows what a method has to beat: the nearest keyframe and the depth warp of the
/// frames captured so far (KeyframeBaselines). Views of a second method on "compare_views" (the
/// demo's P2I-NET beside its default fusion) are scored the same way and printed beside them.
/// Parameters: MonitorOptions (monitor_options.h).
/// Thread-compatible: everything runs on the node's executor thread.
class MonitorNode : public runtime::Node {
 public:
  explicit MonitorNode(const runtime::NodeArgs& args);

 protected:
  void OnShutdown() override;

 private:
  /// Image scores of one view's set (the served views, or the compared method's).
  struct ViewScores {
    std::string method;  ///< ViewMeta.method of the last view scored
    uint64_t scored = 0;
    std::vector<double> psnr, ssim, lpips, depth_absrel, observed_fraction;
  };
  void OnView(const msgs::View& view);
  void OnCompareView(const msgs::View& view);
  /// Scores `view` against the sim ground truth at its pose into `scores`; returns the truth
  /// (at the view's size).
  scene::RgbdSample Score(const msgs::View& view, ViewScores* scores);
  void Finish();
  std::string SummaryText() const;

  std::optional<scene::SimScene> sim_;
  scene::CameraInfo sim_camera_;
  std::unique_ptr<model::LpipsSqueeze> lpips_;
  std::string lpips_status_;
  MonitorOptions options_;
  std::chrono::steady_clock::time_point start_;
  bool finished_ = false;

  uint64_t frames_captured_ = 0;
  uint64_t views_received_ = 0;
  uint64_t views_scored_ = 0;
  std::set<uint64_t> versions_published_;
  std::set<uint64_t> versions_served_;
  ViewScores served_;   ///< the views on "views"
  ViewScores compare_;  ///< the views on "compare_views" (another method on the same poses)
  uint64_t compare_received_ = 0;
  std::vector<double> latency_ms_, render_ms_;
  std::vector<double> coverage_;
  std::optional<KeyframeBaselines> baselines_;  ///< after sim_ (points to it)
  std::vector<double> nearest_psnr_, nearest_ssim_, warp_psnr_, warp_ssim_;
  std::shared_ptr<runtime::RawSubscriber> views_sub_, compare_sub_, frames_sub_, versions_sub_;
};

}  // namespace p2i::nodes
