/// @file trainer_resume_test.cc
/// @brief Exact resume in phase 2 (ENET) and for the CNN baseline, trained by the same Trainer.
#include <unistd.h>

#include <filesystem>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/networks.h"
#include "model/p2i_config.h"
#include "model/export.h"
#include "model/p2i_synthesizer.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "tests/model/model_test_util.h"

namespace fs = std::filesystem;
using namespace p2i::model;
using namespace p2i::model::testing;


TEST_CASE("phase 2 (ENET, G frozen) resumes exactly", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = TinyConfig("p2i_net");
  const auto dir_a = TempDir("p2_a"), dir_b = TempDir("p2_b"), dir_s = TempDir("p2_s");
  // Same phase-1 start for both, then 6 phase-2 steps straight vs 3 + resume to 6.
  Trainer(c, Quiet(dir_a, 3, 1)).Run(data, data);
  fs::copy_file(Trainer::CheckpointPath(dir_a), Trainer::CheckpointPath(dir_b));
  fs::copy_file(Trainer::CheckpointPath(dir_a), Trainer::CheckpointPath(dir_s));
  Trainer(c, Quiet(dir_a, 6, 2)).Run(data, data);
  Trainer(c, Quiet(dir_b, 3, 2)).Run(data, data);
  const auto report = Trainer(c, Quiet(dir_b, 6, 2, /*resume=*/true)).Run(data, data);
  CHECK(report.phase2_steps == 6);
  Networks a(c), b(c), start(c);
  const auto ma = LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  const auto mb = LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK(ma.phase2_step == 6);
  CHECK(mb.phase2_step == 6);
  REQUIRE(a.e);
  REQUIRE(b.e);
  CHECK(SameParameters(*a.e, *b.e));
  CHECK(SameParameters(*a.g, *b.g));
  // G stayed frozen through phase 2, and ENET really trained (it changed from the start).
  LoadCheckpoint(Trainer::CheckpointPath(dir_s), start, {}, false);
  CHECK(SameParameters(*a.g, *start.g));
  REQUIRE(start.e);
  CHECK_FALSE(SameParameters(*a.e, *start.e));
  CHECK(LoadSynthesizer(Trainer::CheckpointPath(dir_a))->Name() == "p2i_net");
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
  fs::remove_all(dir_s);
}

TEST_CASE("the CNN baseline trains by the same Trainer and resumes exactly", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = TinyConfig("cnn_baseline");
  REQUIRE(c.IsBaseline());
  const auto dir_a = TempDir("cnn_a"), dir_b = TempDir("cnn_b");
  Trainer(c, Quiet(dir_a, 6, 0)).Run(data, data);
  Trainer(c, Quiet(dir_b, 3, 0)).Run(data, data);
  Trainer(c, Quiet(dir_b, 6, 0, /*resume=*/true)).Run(data, data);
  Networks a(c), b(c);
  LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK_FALSE(a.d);  // no discriminator for the baseline
  CHECK(SameParameters(*a.g, *b.g));
  torch::manual_seed(c.seed);
  Networks fresh(c);
  CHECK_FALSE(SameParameters(*a.g, *fresh.g));
  auto synth = LoadSynthesizer(Trainer::CheckpointPath(dir_a));
  CHECK(synth->Name() == "cnn_baseline");
  CHECK(synth->Camera().image_width == 32);
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
}

TEST_CASE("the stop hook saves at the current step and --resume continues exactly", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = TinyConfig("p2i_net");
  const auto dir_a = TempDir("stop_a"), dir_b = TempDir("stop_b");
  // Unbroken: 5 phase-1 steps then 5 phase-2 steps.
  Trainer(c, Quiet(dir_a, 5, 0)).Run(data, data);
  // Stopped by the hook after 2 steps (not a checkpoint_every multiple), before phase 2.
  auto stop = Quiet(dir_b, 5, 0);
  int polls = 0;
  stop.should_stop = [&polls] { return ++polls > 2; };
  const auto stopped = Trainer(c, stop).Run(data, data);
  CHECK(stopped.stopped);
  CHECK(stopped.phase1_steps == 2);
  CHECK(stopped.phase2_steps == 0);
  CHECK(ReadCheckpointMeta(Trainer::CheckpointPath(dir_b)).phase1_step == 2);
  const auto resumed = Trainer(c, Quiet(dir_b, 5, 0, /*resume=*/true)).Run(data, data);
  CHECK_FALSE(resumed.stopped);
  CHECK(resumed.phase1_steps == 5);
  CHECK(resumed.phase2_steps == 5);
  Networks a(c), b(c);
  LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK(SameParameters(*a.g, *b.g));
  CHECK(SameParameters(*a.d, *b.d));
  REQUIRE(a.e);
  CHECK(SameParameters(*a.e, *b.e));
  // A hook that never fires changes nothing.
  const auto dir_c = TempDir("stop_c");
  auto never = Quiet(dir_c, 5, 0);
  never.should_stop = [] { return false; };
  CHECK_FALSE(Trainer(c, never).Run(data, data).stopped);
  Networks n(c);
  LoadCheckpoint(Trainer::CheckpointPath(dir_c), n, {}, false);
  CHECK(SameParameters(*a.g, *n.g));
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
  fs::remove_all(dir_c);
}

TEST_CASE("G's moving average (g_ema): saved, resumed exactly, served and exported", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  auto c = TinyConfig("p2i_net");
  c.g_ema = 0.5;
  const auto dir_a = TempDir("ema_a"), dir_b = TempDir("ema_b");
  Trainer(c, Quiet(dir_a, 6, 1)).Run(data, data);
  Trainer(c, Quiet(dir_b, 3, 1)).Run(data, data);
  Trainer(c, Quiet(dir_b, 6, 1, /*resume=*/true)).Run(data, data);
  Networks a(c), b(c);
  REQUIRE(a.g_ema);
  LoadCheckpoint(Trainer::CheckpointPath(dir_a), a, {}, false);
  LoadCheckpoint(Trainer::CheckpointPath(dir_b), b, {}, false);
  CHECK(SameParameters(*a.g, *b.g));
  CHECK(SameParameters(*a.g_ema, *b.g_ema));
  CHECK_FALSE(SameParameters(*a.g, *a.g_ema));  // the average lags the raw G
  // The synthesizer and the export render with the average, not the raw G.
  P2iConfig one = c;
  one.g_ema = 0.0;
  Networks served(one, false);
  LoadServingWeights(Trainer::CheckpointPath(dir_a), served);
  CHECK(SameParameters(*served.g, *a.g_ema));
  const std::string small = dir_a + "/model.pt";
  ExportInference(Trainer::CheckpointPath(dir_a), small);
  Networks exported(one, false);
  LoadWeights(small, exported);
  CHECK(SameParameters(*exported.g, *a.g_ema));
  SynthesizerOptions o;
  o.threads = 1;
  const auto pose = data.frames[5].pose;
  CHECK(cv::norm(LoadSynthesizer(small, o)->Render(pose).rgb,
                 LoadSynthesizer(Trainer::CheckpointPath(dir_a), o)->Render(pose).rgb,
                 cv::NORM_INF) == 0.0);
  fs::remove_all(dir_a);
  fs::remove_all(dir_b);
}
