/// @file cmd_export.cc
/// @brief `p2i export CHECKPOINT --out FILE`: writes the small inference checkpoint (G, ENET,
/// config, pose normalisation, camera; no D, optimiser or RNG state) that rendering and warm
/// starts need (model::ExportInference). With --eval DIR it then renders every frame of a
/// held-out dataset with the exported file and prints PSNR / SSIM (and, with --eval-train DIR,
/// the mean-training-image and nearest-training-frame baselines on the same frames).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>

#include "model/metrics.h"
#include "model/p2i_synthesizer.h"
#include "model/trainer.h"
#include "scene/dataset_loader.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

// As the trainer prepares ground truth: centre square crop, INTER_AREA to side x side.
cv::Mat CropResize(const cv::Mat& in, int side) {
  const int s = std::min(in.cols, in.rows);
  cv::Mat out;
  cv::resize(in(cv::Rect((in.cols - s) / 2, (in.rows - s) / 2, s, s)), out, cv::Size(side, side), 0,
             0, cv::INTER_AREA);
  return out;
}

// RGB PSNR / SSIM of `model` on every frame of `test_dir`; baselines from `train_dir` if given.
void Evaluate(const std::string& model, const std::string& test_dir, const std::string& train_dir,
              int threads) {
  model::SynthesizerOptions o;
  o.threads = threads;
  auto synth = model::LoadSynthesizer(model, o);
  const int r = synth->Camera().image_width;
  const scene::RgbdDataset test = scene::OpenDataset(test_dir).LoadAll();
  if (test.frames.empty()) throw std::runtime_error("--eval " + test_dir + " has no frames");
  scene::RgbdDataset train;
  std::vector<cv::Mat> train_rgb;
  cv::Mat mean;
  if (!train_dir.empty()) {
    train = scene::OpenDataset(train_dir).LoadAll();
    if (train.frames.empty()) throw std::runtime_error("--eval-train " + train_dir + " has no frames");
    cv::Mat sum = cv::Mat::zeros(r, r, CV_64FC3);
    for (const auto& f : train.frames) {
      train_rgb.push_back(CropResize(f.rgb, r));
      cv::accumulate(train_rgb.back(), sum);
    }
    sum.convertTo(mean, CV_8UC3, 1.0 / train_rgb.size());
  }
  double psnr = 0, ssim = 0, mean_psnr = 0, mean_ssim = 0, near_psnr = 0, near_ssim = 0;
  for (const auto& f : test.frames) {
    const cv::Mat gt = CropResize(f.rgb, r);
    const cv::Mat view = synth->Render(f.pose).rgb;
    psnr += model::Psnr(view, gt);
    ssim += model::Ssim(view, gt);
    if (train_rgb.empty()) continue;
    mean_psnr += model::Psnr(mean, gt);
    mean_ssim += model::Ssim(mean, gt);
    // Nearest training pose: metres + 0.5 m per radian of rotation.
    size_t best = 0;
    double best_d = 1e300;
    for (size_t k = 0; k < train.frames.size(); ++k) {
      const auto& q = train.frames[k].pose;
      const double d = (q.translation() - f.pose.translation()).norm() +
                       0.5 * q.rotation().angularDistance(f.pose.rotation());
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    near_psnr += model::Psnr(train_rgb[best], gt);
    near_ssim += model::Ssim(train_rgb[best], gt);
  }
  const double n = static_cast<double>(test.frames.size());
  std::printf("eval %s (%s) on %zu frames of %s at %dx%d: PSNR %.2f dB, SSIM %.3f\n", model.c_str(),
              synth->Name().c_str(), test.frames.size(), test_dir.c_str(), r, r, psnr / n, ssim / n);
  if (!train_rgb.empty())
    std::printf("baselines from %s: mean training image PSNR %.2f dB, SSIM %.3f; nearest training "
                "frame PSNR %.2f dB, SSIM %.3f\n",
                train_dir.c_str(), mean_psnr / n, mean_ssim / n, near_psnr / n, near_ssim / n);
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
    return app.exit(e);
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
