/// @file cmd_export.cc
/// @brief `p2i export CHECKPOINT --out FILE`: writes the small inference checkpoint (G, ENET,
/// config, pose normalisation, camera; no D, optimiser or RNG state) that rendering and warm
/// starts need (model::ExportInference). With --eval DIR it then renders every frame of a
/// held-out dataset with the exported file and prints PSNR / SSIM (and, with --eval-train DIR,
/// the mean-training-image, nearest-training-frame and depth-warp baselines on the same frames).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>

#include "model/baseline_nearest.h"
#include "model/baseline_warp.h"
#include "model/metrics.h"
#include "model/p2i_synthesizer.h"
#include "model/export.h"
#include "model/pose_dependence.h"
#include "scene/dataset_loader.h"
#include "scene/image_ops.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

// RGB PSNR / SSIM of `model` on every frame of `test_dir`; baselines from `train_dir` if given.
// Ground truth and training frames are prepared as the trainer prepares them (centre square
// crop, area-resized to the model's side).
void Evaluate(const std::string& model, const std::string& test_dir, const std::string& train_dir,
              int threads) {
  model::SynthesizerOptions o;
  o.threads = threads;
  auto synth = model::LoadSynthesizer(model, o);
  const int r = synth->Camera().image_width;
  const scene::RgbdDataset test =
      scene::CenterCropResizeDataset(scene::OpenDataset(test_dir).LoadAll(), r, r);
  if (test.frames.empty()) throw std::runtime_error("--eval " + test_dir + " has no frames");
  std::unique_ptr<model::NearestKeyframe> nearest;
  std::unique_ptr<model::DepthWarp> warp;
  cv::Mat mean;
  if (!train_dir.empty()) {
    scene::RgbdDataset train =
        scene::CenterCropResizeDataset(scene::OpenDataset(train_dir).LoadAll(), r, r);
    if (train.frames.empty()) throw std::runtime_error("--eval-train " + train_dir + " has no frames");
    cv::Mat sum = cv::Mat::zeros(r, r, CV_64FC3);
    for (const auto& f : train.frames) cv::accumulate(f.rgb, sum);
    sum.convertTo(mean, CV_8UC3, 1.0 / static_cast<double>(train.frames.size()));
    model::NearestKeyframeOptions nearest_options;
    nearest_options.metres_per_degree = 0.5 * M_PI / 180.0;  // 0.5 m per radian of rotation
    model::DepthWarpOptions warp_options;  // as the bench configs use it: k 4, holes filled
    warp_options.k = 4;
    warp_options.fill_holes = true;
    warp = std::make_unique<model::DepthWarp>(train, warp_options);
    nearest = std::make_unique<model::NearestKeyframe>(std::move(train), nearest_options);
  }
  model::PoseDependence dependence;
  double psnr = 0, ssim = 0, mean_psnr = 0, mean_ssim = 0, near_psnr = 0, near_ssim = 0;
  double warp_psnr = 0, warp_ssim = 0;
  model::PoseDependence near_dependence;
  for (const auto& f : test.frames) {
    const cv::Mat& gt = f.rgb;
    const cv::Mat view = synth->Render(f.pose).rgb;
    psnr += model::Psnr(view, gt);
    ssim += model::Ssim(view, gt);
    dependence.Add(view, gt);
    if (!nearest) continue;
    mean_psnr += model::Psnr(mean, gt);
    mean_ssim += model::Ssim(mean, gt);
    const cv::Mat near = nearest->Render(f.pose).rgb;
    near_psnr += model::Psnr(near, gt);
    near_ssim += model::Ssim(near, gt);
    near_dependence.Add(near, gt);
    const cv::Mat warped = warp->Render(f.pose).rgb;
    warp_psnr += model::Psnr(warped, gt);
    warp_ssim += model::Ssim(warped, gt);
  }
  const double n = static_cast<double>(test.frames.size());
  std::printf("eval %s (%s) on %zu frames of %s at %dx%d: PSNR %.2f dB, SSIM %.3f\n", model.c_str(),
              synth->Name().c_str(), test.frames.size(), test_dir.c_str(), r, r, psnr / n, ssim / n);
  std::printf("pose-dependence %.3f (per-pixel std of the renders over the %zu eval poses / that "
              "of the ground truth: 1 = varies like the scene, 0 = one image for every pose)\n",
              dependence.Score(), test.frames.size());
  const std::string warning = model::PoseDependenceWarning(dependence.Score());
  if (!warning.empty()) std::printf("%s\n", warning.c_str());
  if (nearest)
    std::printf("baselines from %s: mean training image PSNR %.2f dB, SSIM %.3f; nearest training "
                "frame PSNR %.2f dB, SSIM %.3f (pose-dependence %.3f); depth warp (k 4, holes "
                "filled) PSNR %.2f dB, SSIM %.3f\n",
                train_dir.c_str(), mean_psnr / n, mean_ssim / n, near_psnr / n, near_ssim / n,
                near_dependence.Score(), warp_psnr / n, warp_ssim / n);
}

int RunExport(const std::vector<std::string>& args) {
  CLI::App app{"Write a small inference checkpoint (G + ENET + metadata; no discriminator, "
               "optimiser or RNG state) from a training checkpoint. The synthesizer loads it like "
               "the full one; p2i train --init-from warm-starts from it. Written atomically.",
               "p2i export"};
  std::string in_path, out_path, eval_dir, eval_train_dir;
  int threads = 1;
  app.add_option("checkpoint", in_path, "training checkpoint (e.g. runs/office/checkpoint.pt)")
      ->required();
  app.add_option("--out,-o", out_path, "inference checkpoint to write (e.g. models/office.pt)")
      ->required();
  app.add_option("--eval", eval_dir,
                 "then render every frame of this dataset folder (held out) with the exported "
                 "file and print RGB PSNR / SSIM");
  app.add_option("--eval-train", eval_train_dir,
                 "with --eval: the training dataset, for the mean-image and nearest-frame baselines");
  app.add_option("--threads", threads, "LibTorch threads for --eval")->check(CLI::PositiveNumber);
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  const auto parent = std::filesystem::path(out_path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  const model::ExportReport r = model::ExportInference(in_path, out_path);
  std::printf("exported %s -> %s\n%lld parameters (G and ENET if any), phase 1 %d steps, "
              "phase 2 %d steps\n%.2f MB -> %.2f MB\n",
              in_path.c_str(), out_path.c_str(), static_cast<long long>(r.parameters),
              r.phase1_steps, r.phase2_steps, r.in_bytes / 1e6, r.out_bytes / 1e6);
  std::fflush(stdout);
  if (!eval_dir.empty()) Evaluate(out_path, eval_dir, eval_train_dir, threads);
  return 0;
}

P2I_COMMAND("export", "Write a small inference checkpoint (G, ENET, metadata) from a training one",
            RunExport);

}  // namespace
}  // namespace p2i::tools
