/// @file monitor_node.cc
/// @brief p2i_monitor implementation.
#include "nodes/monitor/monitor_node.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "convert/depth.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "model/metrics.h"
#include "scene/image_ops.h"
#include "util/json_number.h"
#include "util/order_stats.h"

namespace p2i::nodes {
namespace {

using util::Median;
using util::NumberOrNull;
using util::PercentileNearestRank;  // as model::LatencyRecorder

}  // namespace

MonitorNode::MonitorNode(const runtime::NodeArgs& args) : Node("monitor", args) {
  options_ = MonitorOptions::FromParameters(Params());
  options_.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  ParametersDone();
  try {
    sim_.emplace(scene::SimScene::FromSpec(options_.scene));
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  // The camera node's default sim camera.
  sim_camera_ = scene::SimScene::DefaultCamera(options_.camera_width, options_.camera_height);
  baselines_.emplace(&*sim_, sim_camera_);
  lpips_ = model::LpipsSqueeze::TryLoad(options_.lpips_weights, &lpips_status_);
  if (lpips_) {
    lpips_status_ = "LPIPS-Squeeze from " + lpips_->weights_path();
  }
  Log().info("{}", lpips_status_);

  views_sub_ = Subscribe<msgs::View>("views", [this](const msgs::View& v) { OnView(v); });
  compare_sub_ = Subscribe<msgs::View>("compare_views",
                                       [this](const msgs::View& v) { OnCompareView(v); });
  frames_sub_ = Subscribe<msgs::RgbdFrame>("rgbd", [this](const msgs::RgbdFrame& f) {
    ++frames_captured_;
    if (f.meta.has_pose()) baselines_->AddKeyframe(convert::FromMsg(f.meta.pose()));
  });
  versions_sub_ = Subscribe<msgs::pb::ModelVersion>(
      "model_version",
      [this](const msgs::pb::ModelVersion& mv) { versions_published_.insert(mv.version()); });
  start_ = std::chrono::steady_clock::now();
  if (options_.duration > 0) {
    AddTimer(std::chrono::milliseconds(200), [this] {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
      if (elapsed >= options_.duration) Finish();
    });
  }
}

void MonitorNode::OnView(const msgs::View& view) {
  ++views_received_;
  versions_served_.insert(view.meta.model_version());
  render_ms_.push_back(view.meta.render_ms());
  latency_ms_.push_back(view.meta.queue_ms() + view.meta.render_ms());
  coverage_.push_back(view.meta.coverage());
  SetValue("views", static_cast<double>(views_received_));
  if ((views_received_ - 1) % options_.score_every != 0) return;
  const scene::RgbdSample truth = Score(view, &served_);
  if (const auto b = baselines_->Score(convert::FromMsg(view.meta.pose()), truth)) {
    nearest_psnr_.push_back(b->nearest_psnr);
    nearest_ssim_.push_back(b->nearest_ssim);
    warp_psnr_.push_back(b->warp_psnr);
    warp_ssim_.push_back(b->warp_ssim);
  }
  ++views_scored_;
}

void MonitorNode::OnCompareView(const msgs::View& view) {
  ++compare_received_;
  if ((compare_received_ - 1) % options_.score_every != 0) return;
  Score(view, &compare_);
}

scene::RgbdSample MonitorNode::Score(const msgs::View& view, ViewScores* s) {
  const cv::Mat rgb = convert::ToMat(view.rgb);
  const cv::Mat depth = convert::DepthToMetres(view.depth);
  scene::RgbdSample truth = sim_->Render(convert::FromMsg(view.meta.pose()), sim_camera_);
  truth = scene::CenterCropResizeSample(truth, rgb.cols, rgb.rows);
  s->method = view.meta.method();
  ++s->scored;
  s->psnr.push_back(model::Psnr(rgb, truth.rgb));
  s->ssim.push_back(model::Ssim(rgb, truth.rgb));
  if (lpips_ && rgb.cols >= 16 && rgb.rows >= 16) s->lpips.push_back(lpips_->Distance(rgb, truth.rgb));
  const model::DepthErrors de = model::ComputeDepthErrors(depth, truth.depth);
  if (std::isfinite(de.abs_rel)) s->depth_absrel.push_back(de.abs_rel);
  if (view.meta.has_observed_fraction()) s->observed_fraction.push_back(view.meta.observed_fraction());
  return truth;
}

namespace {

/// "fusion 24.10 | p2i 17.30 | nearest keyframe 19.92 | depth warp 30.80" (the compared method
/// only when it sent views).
std::string Row(const char* format, const std::string& served, double served_value,
                const std::string& compare, double compare_value, double nearest, double warp) {
  char cell[64];
  std::string out;
  const auto add = [&](const std::string& name, double v) {
    std::snprintf(cell, sizeof(cell), format, v);
    if (!out.empty()) out += " | ";
    out += name + " " + cell;
  };
  add(served.empty() ? "served" : served, served_value);
  if (!compare.empty()) add(compare, compare_value);
  add("nearest keyframe", nearest);
  add("depth warp", warp);
  return out;
}

}  // namespace

// long-function: one line per figure of the printed summary, in the order a user reads them.
std::string MonitorNode::SummaryText() const {
  std::ostringstream os;
  char line[256];
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  os << "==== p2i demo summary (" << static_cast<int>(elapsed) << " s) ====\n";
  os << "frames captured:           " << frames_captured_ << "\n";
  os << "model versions published:  " << versions_published_.size() << "\n";
  os << "model versions served:     " << versions_served_.size() << " (";
  for (auto v : versions_served_) os << " " << v;
  os << " )\n";
  os << "views served:              " << views_received_ << " (" << views_scored_
     << " scored against the sim ground truth, method " << served_.method << ")\n";
  const std::string compare = compare_.scored > 0 ? compare_.method : "";
  if (!compare.empty())
    os << "views compared:            " << compare_.scored << " of " << compare << " (scored the "
       << "same way, on the same planned trajectory)\n";
  std::snprintf(line, sizeof(line), "latency (queue+render) ms: p50 %.1f  p99 %.1f\n",
                Median(latency_ms_), PercentileNearestRank(latency_ms_, 99));
  os << line;
  os << "PSNR dB (median):          "
     << Row("%.2f", served_.method, Median(served_.psnr), compare, Median(compare_.psnr),
            Median(nearest_psnr_), Median(warp_psnr_))
     << "\n";
  os << "SSIM (median):             "
     << Row("%.3f", served_.method, Median(served_.ssim), compare, Median(compare_.ssim),
            Median(nearest_ssim_), Median(warp_ssim_))
     << "\n";
  if (lpips_) {
    std::snprintf(line, sizeof(line), "LPIPS-Squeeze (median):    %.3f", Median(served_.lpips));
    os << line;
    if (!compare.empty()) {
      std::snprintf(line, sizeof(line), " (%s %.3f)", compare.c_str(), Median(compare_.lpips));
      os << line;
    }
    os << "\n";
  } else {
    os << "LPIPS-Squeeze:             missing (" << lpips_status_ << ")\n";
  }
  std::snprintf(line, sizeof(line), "depth AbsRel (median):     %.3f", Median(served_.depth_absrel));
  os << line;
  if (!compare.empty()) {
    std::snprintf(line, sizeof(line), " (%s %.3f)", compare.c_str(), Median(compare_.depth_absrel));
    os << line;
  }
  os << "\n";
  if (!served_.observed_fraction.empty()) {
    std::snprintf(line, sizeof(line), "observed fraction (median): %.3f (pixels whose surface the "
                  "fused geometry observed)\n", Median(served_.observed_fraction));
    os << line;
  }
  if (!options_.sink_summary.empty() && std::filesystem::exists(options_.sink_summary)) {
    try {
      std::ifstream in(options_.sink_summary);
      const nlohmann::json s = nlohmann::json::parse(in);
      os << "slam_sink summary:         " << s.dump() << "\n";
    } catch (const std::exception& e) {
      os << "slam_sink summary:         unreadable (" << e.what() << ")\n";
    }
  }
  if (!options_.sequence_dir.empty()) {
    os << "TUM sequence written to:   " << options_.sequence_dir << "\n";
  }
  return os.str();
}

void MonitorNode::Finish() {
  if (finished_) return;
  finished_ = true;
  const std::string text = SummaryText();
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
  if (!options_.summary_file.empty()) {
    nlohmann::json j;
    j["frames_captured"] = frames_captured_;
    j["model_versions_published"] = versions_published_.size();
    j["model_versions_served"] = std::vector<uint64_t>(versions_served_.begin(),
                                                       versions_served_.end());
    j["views_served"] = views_received_;
    j["views_scored"] = views_scored_;
    j["method"] = served_.method;
    j["latency_ms_p50"] = NumberOrNull(Median(latency_ms_));
    j["latency_ms_p99"] = NumberOrNull(PercentileNearestRank(latency_ms_, 99));
    j["psnr_db_median"] = NumberOrNull(Median(served_.psnr));
    j["nearest_keyframe_psnr_db_median"] = NumberOrNull(Median(nearest_psnr_));
    j["depth_warp_psnr_db_median"] = NumberOrNull(Median(warp_psnr_));
    j["ssim_median"] = NumberOrNull(Median(served_.ssim));
    j["nearest_keyframe_ssim_median"] = NumberOrNull(Median(nearest_ssim_));
    j["depth_warp_ssim_median"] = NumberOrNull(Median(warp_ssim_));
    j["lpips_squeeze_median"] = lpips_ ? NumberOrNull(Median(served_.lpips)) : nullptr;
    j["depth_absrel_median"] = NumberOrNull(Median(served_.depth_absrel));
    j["observed_fraction_median"] = NumberOrNull(Median(served_.observed_fraction));
    if (compare_.scored > 0) {
      j["compare"] = {{"method", compare_.method},
                      {"views_scored", compare_.scored},
                      {"psnr_db_median", NumberOrNull(Median(compare_.psnr))},
                      {"ssim_median", NumberOrNull(Median(compare_.ssim))},
                      {"depth_absrel_median", NumberOrNull(Median(compare_.depth_absrel))}};
    }
    j["sequence_dir"] = options_.sequence_dir;
    const std::string tmp = options_.summary_file + ".tmp";
    {
      std::ofstream out(tmp);
      out << j.dump(2) << "\n";
    }
    std::filesystem::rename(tmp, options_.summary_file);
  }
  Stop();
}

void MonitorNode::OnShutdown() {
  if (!finished_) Finish();
}

}  // namespace p2i::nodes
