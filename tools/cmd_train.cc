/// @file cmd_train.cc
/// @brief `p2i train CONFIG.yaml --data ... --out DIR`: trains P2I-NET (phase 1, 2 or both) or
/// the CNN baseline with model::Trainer.
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "model/densify.h"
#include "model/p2i_config.h"
#include "model/pose_dependence.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "scene/builtin_dataset.h"
#include "scene/dataset_loader.h"
#include "scene/splits.h"
#include "tools/cli_exit.h"
#include "tools/command.h"

namespace p2i::tools {
namespace {

// Set by SIGINT / SIGTERM: the trainer saves a checkpoint at the current step and returns.
volatile std::sig_atomic_t g_stop = 0;
void OnStopSignal(int) { g_stop = 1; }

// --world-size / --rank / --master ... (data-parallel ranks, docs/DISTRIBUTED.md).
model::DistributedOptions g_distributed;
// --inject-nan-at-step (hidden; tests: the divergence guard's rollback, docs/DISTRIBUTED.md).
int g_inject_nan_at_step = -1;

int Train(const model::P2iConfig& config, const scene::RgbdDataset& train,
          const scene::RgbdDataset& val, const std::string& out_dir, int phase, int steps,
          int threads, bool resume, bool quiet, const std::string& init_from) {
  model::TrainerOptions options;
  options.out_dir = out_dir;
  options.phase = phase;
  options.steps = steps;
  options.threads = threads;
  options.resume = resume;
  options.init_from = init_from;
  options.progress = !quiet;
  options.should_stop = [] { return g_stop != 0; };
  options.distributed = g_distributed;
  options.inject_nan_at_step = g_inject_nan_at_step;
  model::Trainer trainer(config, options);
  // Ctrl-C / SIGTERM stop between steps with a checkpoint (`--resume` continues exactly).
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  const auto report = trainer.Run(train, val);
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  if (report.stopped)
    std::printf("stopped by signal: checkpoint saved at the current step (continue with --resume)\n");
  std::printf("trained '%s': phase 1 %d steps, phase 2 %d steps, rollbacks %d\n"
              "validation PSNR %.2f dB (mean training image: %.2f dB), pose-dependence %.2f\n"
              "checkpoint %s\nlog %s\n",
              config.name.c_str(), report.phase1_steps, report.phase2_steps, report.rollbacks,
              report.val_psnr, report.mean_image_val_psnr, report.val_pose_dependence,
              report.checkpoint_path.c_str(), report.log_path.c_str());
  const std::string warning = model::PoseDependenceWarning(report.val_pose_dependence);
  if (!warning.empty()) std::printf("%s\n", warning.c_str());
  return 0;
}

// The training and validation frames.
struct TrainVal {
  scene::RgbdDataset train, val;
};

// Without a split: every holdout_every-th frame (the middle one of each block) validates.
TrainVal HoldOut(const scene::RgbdDataset& all, int holdout_every) {
  TrainVal out;
  out.train.camera = out.val.camera = all.camera;
  for (size_t i = 0; i < all.frames.size(); ++i)
    (holdout_every > 0 && i % holdout_every == static_cast<size_t>(holdout_every / 2) ? out.val
                                                                                      : out.train)
        .frames.push_back(all.frames[i]);
  return out;
}

// --data (builtin:NAME, procedural or a dataset folder) split by --split or --holdout-every.
TrainVal LoadTrainVal(const model::P2iConfig& config, const std::string& data,
                      const std::string& split_file, int frames, int holdout_every) {
  scene::RgbdDataset all;
  if (scene::IsBuiltinSpec(data)) {
    scene::BuiltinDatasetOptions o;
    o.width = o.height = std::max(128, config.resolution);
    o.max_frames = frames;
    std::fprintf(stderr, "rendering up to %d frames of %s along the default arm sweep at %dx%d...\n",
                 frames, data.c_str(), o.width, o.height);
    all = scene::RenderBuiltinDataset(data, o);
  } else if (data == "procedural") {
    all = model::MakeProceduralDataset(frames, std::max(64, config.resolution));
  } else {
    const scene::DatasetIndex index = scene::OpenDataset(data);
    if (!split_file.empty()) {
      const scene::Split split = scene::Split::FromYamlFile(split_file);
      std::fprintf(stderr, "loading %zu training and %zu held-out frames of %s...\n",
                   split.train.size(), split.test.size(), data.c_str());
      TrainVal out;
      out.train = index.SelectIds(split.train).LoadAll();
      out.val = index.SelectIds(split.test).LoadAll();
      return out;
    }
    std::fprintf(stderr, "loading %zu frames of %s...\n", index.size(), data.c_str());
    all = index.LoadAll();
  }
  if (!split_file.empty() && all.frames.size() > 0)
    throw std::runtime_error("--split needs --data DIR (a dataset folder)");
  return HoldOut(all, holdout_every);
}

int RunTrain(const std::vector<std::string>& args) {
  CLI::App app{"Train P2I-NET (phase 1: G+D adversarial, phase 2: ENET) or the CNN baseline.\n"
               "Writes DIR/checkpoint.pt (atomic) and DIR/train_log.jsonl. Ctrl-C or SIGTERM "
               "stops between steps with a checkpoint; --resume continues exactly.",
               "p2i train"};
  std::string config_path, data, split_file, out_dir, init_from;
  std::vector<std::string> overrides;
  int phase = 0, steps = -1, threads = 2, frames = 300, holdout_every = 10;
  bool resume = false, quiet = false;
  app.add_option("config", config_path, "model config YAML (e.g. model/presets/default.yaml)")
      ->required();
  app.add_option("--set", overrides,
                 "KEY=VALUE: override one model config key (repeatable; VALUE is YAML), e.g. "
                 "--set densify_ratio=3 --set recon_weight=200; the checkpoint keeps the result")
      ->allow_extra_args(false);
  app.add_option("--data", data,
                 "dataset folder (p2i capture, TUM RGB-D or 7-Scenes layout), builtin:NAME "
                 "(a built-in sim scene rendered along the default arm sweep with the sim "
                 "camera, as the synthesizer's dataset parameter) or procedural (an analytic "
                 "test room)")
      ->required();
  app.add_option("--split", split_file, "split YAML (docs/DATASETS.md, scene/splits.h): train on its train ids, validate on its "
                 "test ids");
  app.add_option("--out", out_dir, "output directory")->required();
  app.add_option("--phase", phase, "0 = both phases (default), 1 or 2")->check(CLI::Range(0, 2));
  app.add_option("--steps", steps, "train each phase run up to this step (default: config)")
      ->check(CLI::Range(0, 1 << 30));
  app.add_option("--threads", threads, "LibTorch threads")->check(CLI::PositiveNumber);
  app.add_option("--frames", frames,
                 "builtin: at most this many frames, evenly spaced along the sweep; procedural: "
                 "number of frames")
      ->check(CLI::Range(1, 1 << 20));
  app.add_option("--holdout-every", holdout_every,
                 "without --split: every N-th frame is held out for validation PSNR");
  app.add_flag("--resume", resume, "continue exactly from DIR/checkpoint.pt");
  app.add_flag("--quiet", quiet, "no progress bar");
  app.add_option("--init-from", init_from,
                 "warm start (without --resume): G/ENET weights, pose normalisation and step "
                 "counters from this checkpoint (full or `p2i export`ed); D and optimisers fresh");
  app.add_option("--world-size", g_distributed.world_size,
                 "data-parallel: number of ranks (processes, on any hosts; docs/DISTRIBUTED.md)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rank", g_distributed.rank, "data-parallel: this process's rank, 0..N-1");
  app.add_option("--master", g_distributed.master,
                 "data-parallel: HOST:PORT where rank 0 meets the others (e.g. 10.0.0.1:29500)");
  app.add_option("--dist-address", g_distributed.address,
                 "data-parallel: this rank's address for Gloo (default: 127.0.0.1 for a "
                 "loopback master, else the host name's)");
  app.add_option("--dist-timeout", g_distributed.timeout_s,
                 "data-parallel: seconds to wait for the other ranks (rendezvous, each step)");
  app.add_option("--inject-nan-at-step", g_inject_nan_at_step,
                 "fault injection for tests: poison the phase-1 loss with NaN once at this step")
      ->group("");  // hidden
  std::vector<std::string> rev(args.rbegin(), args.rend() - 1);
  try {
    app.parse(rev);
  } catch (const CLI::ParseError& e) {
    return CliExit(app, e);
  }
  const model::P2iConfig config = model::P2iConfig::FromYamlFile(config_path, overrides);
  const TrainVal data_split = LoadTrainVal(config, data, split_file, frames, holdout_every);
  model::DensifyReport dr;
  const scene::RgbdDataset train = model::DensifyTrainingFrames(data_split.train, config, &dr);
  const std::string densified = model::DensifySummary(dr, config);
  if (!densified.empty()) std::fprintf(stderr, "%s\n", densified.c_str());
  return Train(config, train, data_split.val, out_dir, phase, steps, threads, resume, quiet,
               init_from);
}

P2I_COMMAND("train", "Train P2I-NET or the CNN baseline from a config preset", RunTrain);

}  // namespace
}  // namespace p2i::tools
