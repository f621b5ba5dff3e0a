/// @file trainer_resume_test.cc
/// @brief Exact resume in phase 2 (ENET) and for the CNN baseline, trained by the same Trainer.
#include <unistd.h>

#include <filesystem>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/networks.h"
#include "model/p2i_config.h"
#include "model/p2i_synthesizer.h"
#include "model/trainer.h"

namespace fs = std::filesystem;
using namespace p2i::model;

namespace {

std::string FreshDir(const std::string& name) {
  const auto dir = fs::temp_directory_path() /
                   ("p2i_resume_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

P2iConfig Tiny(const std::string& model) {
  P2iConfig c;
  c.name = "tiny_" + model;
  c.model = model;
  c.resolution = 32;
  c.g_schedule = "custom";
  c.g_widths = {16, 16, 8, 8};
  c.g_fc_width = 16;
  c.d_base_width = 8;
  c.d_max_width = 16;
  c.latent_dim = 32;
  c.mapping_width = 16;
  c.enet_width = 8;
  c.enet_blocks = 1;
  c.batch_size = 4;
  c.val_every = 5;
  c.checkpoint_every = 3;
  c.Validate();
  return c;
}

TrainerOptions Opts(const std::string& dir, int steps, int phase, bool resume = false) {
  TrainerOptions o;
  o.out_dir = dir;
  o.steps = steps;
  o.phase = phase;
  o.threads = 1;
  o.progress = false;
  o.max_val_frames = 4;
  o.resume = resume;
  return o;
}

bool Same(torch::nn::Module& a, torch::nn::Module& b) {
  auto pa = a.named_parameters(), pb = b.named_parameters();
  if (pa.size() != pb.size()) return false;
  for (const auto& kv : pa)
    if (!torch::equal(kv.value(), pb[kv.key()])) return false;
  return true;
}

}  // namespace

TEST_CASE("phase 2 (ENET, G frozen) resumes exactly", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = Tiny("p2i_net");
  const auto dir_a = FreshDir("p2_a"), dir_b = FreshDir("p2_b"), dir_s = FreshDir("p2_s");
  // Same phase-1 start for both, then 6 phase-2 steps straight vs 3 + resume to 6.
  Trainer(c, Opts(dir_a, 3, 1)).Run(data, data);
  fs::copy_file(Trainer::CheckpointPath(dir_a), Trainer::CheckpointPath(dir_b));
  fs::copy_file(Trainer::CheckpointPath(dir_a), Trainer::CheckpointPath(dir_s));
  Trainer(c, Opts(dir_a, 6, 2)).Run(data, data);
  Trainer(c, Opts(dir_b, 3, 2)).Run(data, data);
  const auto report = Trainer(c, Opts(dir_b, 6, 2, /*resume=*/true)).Run(data, data);
  CHECK(report.phase2_steps == 6);
  Networks a(c), b(c), start(c);
  const auto ma = LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  const auto mb = LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK(ma.phase2_step == 6);
  CHECK(mb.phase2_step == 6);
  REQUIRE(a.e);
  REQUIRE(b.e);
  CHECK(Same(*a.e, *b.e));
  CHECK(Same(*a.g, *b.g));
  // G stayed frozen through phase 2, and ENET really trained (it changed from the start).
  LoadCheckpoint(Trainer::CheckpointPath(dir_s), start, {}, false);
  CHECK(Same(*a.g, *start.g));
  REQUIRE(start.e);
  CHECK_FALSE(Same(*a.e, *start.e));
  CHECK(LoadSynthesizer(Trainer::CheckpointPath(dir_a))->Name() == "p2i_net");
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
  fs::remove_all(dir_s);
}

TEST_CASE("the CNN baseline trains by the same Trainer and resumes exactly", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = Tiny("cnn_baseline");
  REQUIRE(c.IsBaseline());
  const auto dir_a = FreshDir("cnn_a"), dir_b = FreshDir("cnn_b");
  Trainer(c, Opts(dir_a, 6, 0)).Run(data, data);
  Trainer(c, Opts(dir_b, 3, 0)).Run(data, data);
  Trainer(c, Opts(dir_b, 6, 0, /*resume=*/true)).Run(data, data);
  Networks a(c), b(c);
  LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK_FALSE(a.d);  // no discriminator for the baseline
  CHECK(Same(*a.g, *b.g));
  torch::manual_seed(c.seed);
  Networks fresh(c);
  CHECK_FALSE(Same(*a.g, *fresh.g));
  auto synth = LoadSynthesizer(Trainer::CheckpointPath(dir_a));
  CHECK(synth->Name() == "cnn_baseline");
  CHECK(synth->Camera().image_width == 32);
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
}
