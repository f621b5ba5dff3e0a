/// @file evaluation.cc
/// @brief EvaluateSplit (see evaluation.h).
#include "refine/evaluation.h"

#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>

#include "fusion/fusion_synthesizer.h"
#include "model/baseline_nearest.h"
#include "model/baseline_warp.h"
#include "model/learned_refiner.h"
#include "model/metrics.h"
#include "scene/image_ops.h"

namespace p2i::refine {

void SplitEvalOptions::Validate() const {
  if (width < 8 || height < 8) throw std::invalid_argument("SplitEvalOptions: width/height < 8");
  if (fuse_width < 0 || fuse_height < 0)
    throw std::invalid_argument("SplitEvalOptions: fuse size must be >= 0");
  if (warp_k < 1) throw std::invalid_argument("SplitEvalOptions: warp_k must be >= 1");
  loo.Validate();
  finetune.Validate();
}

namespace {

struct Acc {
  MethodScore s;
  int depth_views = 0;
  void Add(const scene::RgbdSample& view, const scene::RgbdSample& gt) {
    s.psnr += model::Psnr(view.rgb, gt.rgb);
    s.ssim += model::Ssim(view.rgb, gt.rgb);
    const model::DepthErrors d = model::ComputeDepthErrors(view.depth, gt.depth);
    if (std::isfinite(d.abs_rel)) {
      s.abs_rel += d.abs_rel;
      ++depth_views;
    }
    ++s.views;
  }
  MethodScore Done() {
    if (s.views > 0) {
      s.psnr /= s.views;
      s.ssim /= s.views;
      s.observed /= s.views;
    }
    if (depth_views > 0) s.abs_rel /= depth_views;
    return s;
  }
};

/// The frames resized to w x h with their calibration (CameraInfo::Scaled: pixel centres at
/// integers, as cv::resize samples them; scaling the principal point by the size ratio alone put
/// it a quarter pixel off at half size).
scene::RgbdDataset Resized(const scene::RgbdDataset& d, int w, int h) {
  if (w <= 0 || h <= 0) return d;
  scene::RgbdDataset out;
  out.camera = d.camera.Scaled(w, h);
  for (const auto& f : d.frames) out.frames.push_back(scene::ResizeSample(f, w, h));
  return out;
}

/// Nearest keyframe and depth warp (holes filled) over the training frames, on the test frames.
std::vector<MethodScore> ScoreBaselines(const scene::RgbdDataset& train, const scene::RgbdDataset& test,
                                        int warp_k) {
  Acc nearest{{"nearest"}}, warp{{"warp"}};
  model::NearestKeyframe nk(train);
  model::DepthWarpOptions wo;
  wo.k = warp_k;
  wo.fill_holes = true;
  model::DepthWarp dw(train, wo);
  for (const auto& gt : test.frames) {
    nearest.Add(nk.Render(gt.pose), gt);
    warp.Add(dw.Render(gt.pose), gt);
  }
  return {nearest.Done(), warp.Done()};
}

/// The plain blend of each test view's candidates as the fusion method serves it (fusion::ToView
/// with fill_holes, its default): the pixels no surface covers push-pull filled, not left black.
MethodScore ScoreBlend(const std::vector<fusion::ViewCandidates>& cands, const scene::RgbdDataset& test) {
  Acc blend{{"fusion_blend"}};
  for (size_t i = 0; i < cands.size(); ++i) {
    const auto& gt = test.frames[i];
    blend.Add(fusion::ToView(gt.pose, cands[i].blended, cands[i].depth, true, "fusion_blend", cands[i].far), gt);
    blend.s.observed += cands[i].coverage.observed_fraction;
  }
  return blend.Done();
}

}  // namespace

SplitEvalReport EvaluateSplit(const scene::RgbdDataset& train, const scene::RgbdDataset& test,
                              const std::string& net_path, const SplitEvalOptions& options) {
  options.Validate();
  if (train.frames.empty() || test.frames.empty())
    throw std::invalid_argument("EvaluateSplit: empty train or test set");
  SplitEvalReport report;
  report.train_frames = static_cast<int>(train.frames.size());
  report.test_frames = static_cast<int>(test.frames.size());
  const scene::RgbdDataset train_small =
      scene::CenterCropResizeDataset(train, options.width, options.height);
  const scene::RgbdDataset test_small =
      scene::CenterCropResizeDataset(test, options.width, options.height);
  const scene::CameraInfo camera = test_small.camera;
  const scene::RgbdDataset fuse_frames = Resized(train, options.fuse_width, options.fuse_height);

  report.methods = ScoreBaselines(train_small, test_small, options.warp_k);
  // The test views' candidates from a scene fused from every training frame.
  std::vector<fusion::ViewCandidates> cands;
  {
    auto fused = FuseAll(fuse_frames, options.loo.scene, options.loo.keyframe_every);
    for (const auto& gt : test_small.frames) cands.push_back(fused->Render(gt.pose, camera));
  }
  report.methods.push_back(ScoreBlend(cands, test_small));

  const auto score = [&](const std::string& name, fusion::ViewRefiner& r) {
    Acc a{{name}};
    for (size_t i = 0; i < cands.size(); ++i) {
      a.Add(r.Refine(cands[i]), test_small.frames[i]);
      a.s.observed += cands[i].coverage.observed_fraction;
    }
    report.methods.push_back(a.Done());
  };
  const int k = options.loo.scene.k;
  std::vector<model::RefineSample> samples;
  const bool tune = options.finetune.steps > 0;
  if (tune) {
    samples = MakeLeaveOneOutSamples(fuse_frames, camera, options.loo);
    // Fusing at fuse size, rendering at the eval camera: the targets must be the eval frames.
    report.loo_samples = static_cast<int>(samples.size());
  }
  if (!net_path.empty()) {
    auto zero = model::LearnedRefiner::Load(net_path, k);
    score("fusion_refined_zero_shot", *zero);
    if (tune) {
      const auto t0 = std::chrono::steady_clock::now();
      const model::RefineFitReport fit = zero->refiner().Fit(samples, options.finetune);
      report.finetune_seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      report.finetune_first_loss = fit.first_loss;
      report.finetune_last_loss = fit.last_loss;
      score("fusion_refined_finetuned", *zero);
    }
  }
  if (tune && options.scratch) {
    auto fresh = model::LearnedRefiner::Fresh(k);
    fresh->refiner().Fit(samples, options.finetune);
    score("fusion_refined_scratch", *fresh);
  }
  return report;
}

}  // namespace p2i::refine
