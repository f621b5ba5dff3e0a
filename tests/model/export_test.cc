/// @file export_test.cc
/// @brief Inference checkpoints (model::ExportInference, `p2i export`): smaller, render the
/// same views as the full checkpoint, version refusal, and warm starts from them (init_from and
/// resume from an exported file copied into the run folder).
#include <filesystem>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/export.h"
#include "model/p2i_synthesizer.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "tests/model/model_test_util.h"
#include "tests/process_util.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using namespace p2i::model;
using namespace p2i::model::testing;

namespace {

// 4 phase-1 and 3 phase-2 steps of the tiny model in `dir`.
std::string TrainTiny(const std::string& dir, const p2i::scene::RgbdDataset& data) {
  auto o = Quiet(dir, 4, 1);
  Trainer(TinyConfig(), o).Run(data, data);
  o = Quiet(dir, 3, 2);
  return Trainer(TinyConfig(), o).Run(data, data).checkpoint_path;
}

std::vector<p2i::scene::Pose> SomePoses(const p2i::scene::RgbdDataset& data) {
  std::vector<p2i::scene::Pose> poses;
  for (size_t i = 0; i < data.frames.size(); i += 3) poses.push_back(data.frames[i].pose);
  return poses;
}

}  // namespace

TEST_CASE("an exported inference checkpoint is small and renders the same views", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto dir = TempDir("export");
  const std::string full = TrainTiny(dir, data);
  const std::string small = dir + "/model.pt";
  const ExportReport r = ExportInference(full, small);
  CHECK(r.in_bytes == static_cast<int64_t>(fs::file_size(full)));
  CHECK(r.out_bytes == static_cast<int64_t>(fs::file_size(small)));
  CHECK(r.phase1_steps == 4);
  CHECK(r.phase2_steps == 3);
  // No D, no Adam moments, no RNG state: well under a third of the training checkpoint.
  CHECK(r.out_bytes * 3 < r.in_bytes);
  const CheckpointMeta meta = ReadCheckpointMeta(small);
  CHECK(meta.inference_only);
  CHECK_FALSE(ReadCheckpointMeta(full).inference_only);
  CHECK(meta.config.ToYamlString() == TinyConfig().ToYamlString());
  CHECK(meta.normalizer.t_min == ReadCheckpointMeta(full).normalizer.t_min);
  CHECK(r.parameters == [&] {
    Networks n(TinyConfig());
    return CountParameters(*n.g) + CountParameters(*n.e);
  }());
  // Identical renders (G + ENET, as phase 2 ran) and camera.
  SynthesizerOptions o;
  o.threads = 1;
  auto a = LoadSynthesizer(full, o);
  auto b = LoadSynthesizer(small, o);
  CHECK(b->Name() == "p2i_net");
  CHECK(a->Camera().fx() == b->Camera().fx());
  CHECK(a->ParameterCount() == b->ParameterCount());
  const auto poses = SomePoses(data);
  const auto va = a->RenderBatch(poses), vb = b->RenderBatch(poses);
  REQUIRE(va.size() == vb.size());
  for (size_t i = 0; i < va.size(); ++i) {
    CHECK(cv::norm(va[i].rgb, vb[i].rgb, cv::NORM_INF) == 0.0);
    CHECK(cv::norm(va[i].depth, vb[i].depth, cv::NORM_INF) == 0.0);
  }
  // It cannot be resumed as a training checkpoint: the message says what it is.
  Networks n(TinyConfig());
  CHECK_THROWS_WITH(LoadCheckpoint(small, n, {}, false),
                    Catch::Contains("inference checkpoint") && Catch::Contains("--init-from"));
  fs::remove_all(dir);
}

TEST_CASE("an inference checkpoint of another format version is refused clearly", "[unit]") {
  const auto dir = TempDir("export_version");
  const auto c = TinyConfig();
  Networks n(c, /*with_discriminator=*/false);
  CheckpointMeta meta;
  meta.config = c;
  meta.inference_only = true;
  meta.format_version = kCheckpointFormatVersion + 1;
  SaveCheckpoint(dir + "/future.pt", meta, n, {});
  // (Catch's && keeps references to its operands: both matchers must outlive the checks.)
  const auto version = Catch::Contains("format version " + std::to_string(kCheckpointFormatVersion + 1));
  const auto reads = Catch::Contains("this build reads version");
  const auto refused = version && reads;
  CHECK_THROWS_WITH(LoadSynthesizer(dir + "/future.pt"), refused);
  CHECK_THROWS_WITH(ExportInference(dir + "/future.pt", dir + "/out.pt"), refused);
  CHECK_FALSE(fs::exists(dir + "/out.pt"));
  CHECK_THROWS_WITH(ExportInference(dir + "/missing.pt", dir + "/out.pt"),
                    Catch::Contains("does not exist"));
  auto o = Quiet(dir + "/run", 2, 1);
  o.init_from = dir + "/future.pt";
  const auto data = MakeProceduralDataset(6, 32);
  CHECK_THROWS_WITH(Trainer(c, o).Run(data, data), refused);
  fs::remove_all(dir);
}

TEST_CASE("warm start from an exported checkpoint: G/ENET loaded, D fresh, trains on", "[unit]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto c = TinyConfig();
  const auto dir = TempDir("warm");
  const std::string small = dir + "/model.pt";
  ExportInference(TrainTiny(dir + "/src", data), small);
  Networks exported(c, false);
  LoadWeights(small, exported);

  // init_from with 0 further steps: the weights are exactly the exported ones, D is fresh.
  auto o = Quiet(dir + "/a", 4, 1);  // the source is at phase-1 step 4 already
  o.init_from = small;
  auto report = Trainer(c, o).Run(data, data);
  CHECK(report.phase1_steps == 4);
  CHECK(report.phase2_steps == 3);  // the ENET came along, still counted as trained
  {
    Networks n(c);
    const auto meta = LoadCheckpoint(report.checkpoint_path, n, {}, false);  // a full one now
    CHECK_FALSE(meta.inference_only);
    CHECK(SameParameters(*n.g, *exported.g));
    CHECK(SameParameters(*n.e, *exported.e));
    torch::manual_seed(c.seed);
    Networks fresh(c);
    CHECK(SameParameters(*n.d, *fresh.d));
  }
  // It trains on from there: G changes, the step counter continues.
  o = Quiet(dir + "/a", 8, 1, /*resume=*/true);
  report = Trainer(c, o).Run(data, data);
  CHECK(report.phase1_steps == 8);
  {
    Networks n(c);
    LoadCheckpoint(report.checkpoint_path, n, {}, false);
    CHECK_FALSE(SameParameters(*n.g, *exported.g));
    for (const auto& p : n.g->parameters()) REQUIRE(torch::isfinite(p).all().item<bool>());
  }
  // The trainer node's path: the exported file copied into the run folder, then --resume.
  fs::create_directories(dir + "/b");
  fs::copy_file(small, Trainer::CheckpointPath(dir + "/b"));
  report = Trainer(c, Quiet(dir + "/b", 6, 1, /*resume=*/true)).Run(data, data);
  CHECK(report.phase1_steps == 6);
  CHECK_FALSE(ReadCheckpointMeta(report.checkpoint_path).inference_only);
  // Another shape is refused, naming the file.
  auto wider = c;
  wider.g_widths = {32, 16, 8, 8};
  auto bad = Quiet(dir + "/c", 6, 1);
  bad.init_from = small;
  CHECK_THROWS_WITH(Trainer(wider, bad).Run(data, data),
                    Catch::Contains(small) && Catch::Contains("another shape"));
  fs::remove_all(dir);
}

TEST_CASE("p2i export writes the inference checkpoint, reports sizes and --eval quality",
          "[integration]") {
  const auto data = MakeProceduralDataset(12, 32);
  const auto dir = TempDir("export_cli");
  const std::string full = TrainTiny(dir, data);
  int code = -1;
  const std::string out = p2i::testing::RunCommand(
      p2i::testing::BinDir() + "/p2i export " + full + " --out " + dir + "/models/m.pt 2>&1", &code);
  INFO(out);
  CHECK(code == 0);
  CHECK(out.find("MB ->") != std::string::npos);
  REQUIRE(fs::exists(dir + "/models/m.pt"));
  CHECK(ReadCheckpointMeta(dir + "/models/m.pt").inference_only);
  // --eval: held-out quality of the exported file on a rendered dataset, with baselines.
  const std::string bin = p2i::testing::BinDir() + "/p2i";
  p2i::testing::RunCommand(bin + " render builtin:small_office -t adjacent_sweeps --width 40 "
                           "--height 32 --max-frames 4 --out " + dir + "/data 2>&1", &code);
  REQUIRE(code == 0);
  const std::string eval = p2i::testing::RunCommand(
      bin + " export " + full + " --out " + dir + "/m2.pt --eval " + dir + "/data/seq-02 " +
          "--eval-train " + dir + "/data/seq-01 2>&1", &code);
  INFO(eval);
  CHECK(code == 0);
  CHECK(eval.find("on 4 frames") != std::string::npos);
  CHECK(eval.find("SSIM") != std::string::npos);
  CHECK(eval.find("nearest training frame PSNR") != std::string::npos);
  CHECK(eval.find("depth warp (k 4, holes filled) PSNR") != std::string::npos);
  CHECK(eval.find("pose-dependence ") != std::string::npos);
  const std::string bad = p2i::testing::RunCommand(
      p2i::testing::BinDir() + "/p2i export " + dir + "/nope.pt --out " + dir + "/x.pt 2>&1", &code);
  CHECK(code != 0);
  CHECK(bad.find("nope.pt does not exist") != std::string::npos);
  fs::remove_all(dir);
}
