/// @file cmd_refine.cc
/// @brief `p2i refine train-sim --out FILE`: trains the cross-scene refinement net of the fusion
/// method on randomised sim scenes (leave-one-out). `p2i refine eval --data DIR --net FILE`:
/// nearest keyframe, depth warp, the plain fusion blend, the refinement zero-shot and fine-tuned
/// on each split's own leave-one-out samples, on the same test frames (docs/EVALUATION.md
/// "p2i refine", figures in docs/RESULTS.md "Refinement on real data").
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "refine/cross_scene.h"
#include "refine/evaluation.h"
#include "scene/dataset_loader.h"
#include "scene/splits.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

int RunTrainSim(const std::vector<std::string>& args) {
  CLI::App app{"Train the cross-scene refinement net on randomised sim scenes (leave-one-out)",
               "p2i refine train-sim"};
  refine::CrossSceneOptions o;
  std::string out;
  double pose_noise_cm = 0.0;
  app.add_option("--out,-o", out, "refinement file to write (e.g. models/refine_sim.pt)")->required();
  app.add_option("--scenes", o.scenes.scenes, "randomised scenes (the last --held-out only validate)");
  app.add_option("--held-out", o.held_out_scenes, "scenes kept for validation");
  app.add_option("--frames", o.scenes.frames, "frames per scene");
  app.add_option("--frame-step", o.scenes.frame_step,
                 "poses of the 20 Hz walk between kept frames (5 = 5 cm and up to 7.5 degrees apart)");
  app.add_option("--width", o.scenes.width, "frame size");
  app.add_option("--height", o.scenes.height, "frame size");
  app.add_option("--seed", o.scenes.seed, "scene randomisation seed");
  app.add_option("--sensor", o.scenes.sensor, "sensor model of the noisy scenes: kinect or realistic")
      ->check(CLI::IsMember({"kinect", "realistic"}));
  app.add_option("--pixel-samples", o.scenes.pixel_samples,
                 "rays per pixel side of the sim renders (odd, 1-7; 3 = pixels that integrate over "
                 "their area, as a real camera's)");
  app.add_option("--pose-noise-cm", pose_noise_cm,
                 "recorded-pose error, translation sigma (cm; each scene draws a scale in [0, 1])");
  app.add_option("--pose-noise-deg", o.scenes.pose_noise_deg,
                 "recorded-pose error, rotation sigma (degrees; same per-scene scale)");
  app.add_option("--steps", o.fit.steps, "Adam steps");
  app.add_option("--batch", o.fit.batch_size, "batch size");
  app.add_option("--lr", o.fit.lr, "learning rate");
  app.add_option("--crop", o.fit.crop, "random square crops (0 = whole views)");
  app.add_option("--threads", o.fit.threads, "LibTorch threads");
  app.add_option("--voxel", o.loo.scene.voxel_size_m, "TSDF voxel size (m)");
  app.add_option("--folds", o.loo.folds, "leave-one-out folds");
  app.add_option("--widths", o.net.widths, "U-Net widths per level");
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  o.scenes.pose_noise_m = pose_noise_cm / 100.0;
  const auto parent = std::filesystem::path(out).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent);
  const refine::CrossSceneReport r = refine::TrainCrossScene(o, out);
  std::printf("%d train / %d held-out leave-one-out samples (%.1f s), %lld parameters\n"
              "fit: %d steps in %.1f s, loss %.4f -> %.4f\n"
              "held-out scenes: blend PSNR %.2f dB SSIM %.3f, refined PSNR %.2f dB SSIM %.3f (%d views)\n"
              "wrote %s (%.2f MB)\n",
              r.train_samples, r.val_samples, r.seconds_samples,
              static_cast<long long>(r.parameters), r.fit.steps, r.seconds_fit, r.fit.first_loss,
              r.fit.last_loss, r.val.psnr_blend, r.val.ssim_blend, r.val.psnr_refined,
              r.val.ssim_refined, r.val.views, out.c_str(),
              std::filesystem::file_size(out) / 1e6);
  return 0;
}

int RunEval(const std::vector<std::string>& args) {
  CLI::App app{"Refinement figures on a dataset's missing-frames splits", "p2i refine eval"};
  std::string data, net, json_out;
  std::vector<int> held_out{1, 3};
  int period = 10;
  refine::SplitEvalOptions o;
  o.finetune.steps = 300;
  app.add_option("--data", data, "dataset folder (e.g. ../shared/data/study-room)")->required();
  app.add_option("--net", net, "zero-shot refinement file (e.g. models/refine_sim.pt)");
  app.add_option("--held-out", held_out, "settings a<N>: N of every --period frames held out");
  app.add_option("--period", period, "setting (a) period");
  app.add_option("--width", o.width, "view size");
  app.add_option("--height", o.height, "view size");
  app.add_option("--finetune-steps", o.finetune.steps, "fine-tuning Adam steps (0 = none)");
  app.add_option("--lr", o.finetune.lr, "fine-tuning learning rate");
  app.add_option("--batch", o.finetune.batch_size, "fine-tuning batch size");
  app.add_option("--threads", o.finetune.threads, "LibTorch threads");
  app.add_option("--voxel", o.loo.scene.voxel_size_m, "TSDF voxel size (m)");
  app.add_option("--folds", o.loo.folds, "leave-one-out folds");
  app.add_flag("!--no-scratch", o.scratch, "skip the per-scene net trained from scratch");
  app.add_option("--json", json_out, "also write the figures as JSON here");
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  const scene::DatasetIndex index = scene::OpenDataset(data);
  nlohmann::json all = nlohmann::json::array();
  for (int n : held_out) {
    const scene::Split split = scene::MakeMissingFramesSplit(index, n, period);
    const scene::RgbdDataset train = index.SelectIds(split.train).LoadAll();
    const scene::RgbdDataset test = index.SelectIds(split.test).LoadAll();
    const refine::SplitEvalReport r = refine::EvaluateSplit(train, test, net, o);
    std::printf("setting a%d (period %d): %d train, %d test frames at %dx%d; %d leave-one-out "
                "samples; fine-tune loss %.4f -> %.4f in %.1f s\n",
                n, period, r.train_frames, r.test_frames, o.width, o.height, r.loo_samples,
                r.finetune_first_loss, r.finetune_last_loss, r.finetune_seconds);
    std::printf("  %-28s %8s %7s %8s %9s\n", "method", "PSNR dB", "SSIM", "AbsRel", "observed");
    for (const auto& m : r.methods) {
      std::printf("  %-28s %8.2f %7.3f %8.3f %9.3f\n", m.method.c_str(), m.psnr, m.ssim,
                  m.abs_rel, m.observed);
      all.push_back({{"setting", "a" + std::to_string(n)}, {"method", m.method},
                     {"psnr", m.psnr}, {"ssim", m.ssim}, {"abs_rel", m.abs_rel},
                     {"observed", m.observed}, {"views", m.views}});
    }
    std::fflush(stdout);
  }
  if (!json_out.empty()) std::ofstream(json_out) << all.dump(2) << "\n";
  return 0;
}

int RunRefine(const std::vector<std::string>& args) {
  if (args.size() >= 2 && args[1] == "train-sim")
    return RunTrainSim(std::vector<std::string>(args.begin() + 1, args.end()));
  if (args.size() >= 2 && args[1] == "eval")
    return RunEval(std::vector<std::string>(args.begin() + 1, args.end()));
  const bool help = args.size() >= 2 && (args[1] == "--help" || args[1] == "-h");
  std::fprintf(help ? stdout : stderr, "usage: p2i refine train-sim --out FILE [options] | p2i refine eval "
                       "--data DIR --net FILE [options] (--help on each)\n");
  return help ? 0 : 2;
}

P2I_COMMAND("refine", "Train (sim, cross-scene) and evaluate the fusion method's refinement net",
            RunRefine);

}  // namespace
}  // namespace p2i::tools
