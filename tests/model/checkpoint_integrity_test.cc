/// @file checkpoint_integrity_test.cc
/// @brief Torn, poisoned and foreign checkpoints are refused, naming the file and the reason,
/// by every reader: rendering (synthesizer start-up), export (no output, no .tmp left) and warm
/// start (init_from); format-1 files (bare zip) still load; a model whose weights are finite but
/// whose probe view is not is refused by LoadSynthesizer.
#include <filesystem>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/export.h"
#include "model/p2i_synthesizer.h"
#include "model/procedural_dataset.h"
#include "model/trainer.h"
#include "tests/checkpoint_tamper.h"
#include "tests/model/model_test_util.h"
#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/skip.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using namespace p2i::model;
using namespace p2i::model::testing;
using p2i::testing::Damaged;
using p2i::testing::ReadFile;
using p2i::testing::WriteBytes;

namespace {

// An untrained tiny inference checkpoint (format `version`) at dir/name.
std::string TinyInference(const std::string& dir, const std::string& name,
                          int version = kCheckpointFormatVersion) {
  torch::manual_seed(3);
  Networks n(TinyConfig(), /*with_discriminator=*/false);
  CheckpointMeta meta;
  meta.config = TinyConfig();
  meta.normalizer.t_min = {-1, -1, -1};
  meta.normalizer.t_max = {1, 1, 1};
  meta.camera.image_width = meta.camera.image_height = 32;
  meta.inference_only = true;
  meta.format_version = version;
  const std::string path = dir + "/" + name;
  SaveCheckpoint(path, meta, n, {});
  return path;
}

bool AnyTmp(const std::string& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp") != std::string::npos) return true;
  return false;
}

struct Damage {
  const char* kind;
  const char* reason;  // part of the refusal
};

const Damage kDamages[] = {
    {"torn", "truncated"},
    {"random", "not a p2i checkpoint"},
    {"empty", "empty"},
    {"version", "format version 99"},
    {"flipped", "corrupted"},
    {"record", "refused"},  // by the storage check or, once LibTorch resized it, the finite one
    {"nan", "non-finite"},
};

}  // namespace

TEST_CASE("the saver writes format 2: header with size, CRC-32 and tensor manifest", "[unit]") {
  const auto dir = TempDir("ckpt_format");
  const std::string path = TinyInference(dir, "good.pt");
  const std::string bytes = ReadFile(path);
  CHECK(bytes.rfind("P2ICKPT 2\n{\"payload_bytes\":", 0) == 0);
  CHECK(bytes.find("\"G/") != std::string::npos);  // manifest entries
  auto s = LoadSynthesizer(path);
  CHECK(s->Name() == "p2i_net_g");
  CHECK_FALSE(AnyTmp(dir));
  fs::remove_all(dir);
}

TEST_CASE("damaged checkpoints are refused by start-up, export and warm start", "[unit]") {
  const auto dir = TempDir("ckpt_damage");
  const std::string good = ReadFile(TinyInference(dir, "good.pt"));
  const auto data = MakeProceduralDataset(6, 32);
  for (const Damage& d : kDamages) {
    SECTION(d.kind) {
      const std::string bad = dir + "/" + d.kind + ".pt";
      WriteBytes(bad, Damaged(good, d.kind));
      const auto names_it = Catch::Contains(bad);
      const auto says_why = Catch::Contains(d.reason);
      const auto refused = names_it && says_why;
      // Synthesizer start-up (the factory the node's loader calls).
      CHECK_THROWS_WITH(LoadSynthesizer(bad), refused);
      // Export: refused, no output file, no temporary file left.
      CHECK_THROWS_WITH(ExportInference(bad, dir + "/out.pt"), refused);
      CHECK_FALSE(fs::exists(dir + "/out.pt"));
      CHECK_FALSE(AnyTmp(dir));
      // Warm start.
      auto o = Quiet(dir + "/run_" + d.kind, 2, 1);
      o.init_from = bad;
      CHECK_THROWS_WITH(Trainer(TinyConfig(), o).Run(data, data), refused);
      // The same through the weight loaders (resume path).
      Networks n(TinyConfig(), false);
      CHECK_THROWS_WITH(LoadWeights(bad, n), refused);
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("format-1 checkpoints load, a record cut short in one is refused", "[unit]") {
  const auto dir = TempDir("ckpt_v1");
  const std::string v1_container = ReadFile(TinyInference(dir, "v1_src.pt", 1));
  const auto parts = p2i::testing::SplitCheckpoint(v1_container);
  WriteBytes(dir + "/v1.pt", parts.payload);  // a bare zip, as format 1 wrote it
  auto a = LoadSynthesizer(dir + "/v1.pt");
  auto b = LoadSynthesizer(TinyInference(dir, "v2.pt"));
  const auto pose = p2i::scene::Pose::Identity();
  CHECK(cv::norm(a->Render(pose).rgb, b->Render(pose).rgb, cv::NORM_INF) == 0.0);
  ExportInference(dir + "/v1.pt", dir + "/reexported.pt");  // re-exported as format 2
  CHECK(ReadFile(dir + "/reexported.pt").rfind("P2ICKPT 2\n", 0) == 0);

  WriteBytes(dir + "/v1_cut.pt", Damaged(v1_container, "record_v1"));
  CHECK_THROWS_WITH(LoadSynthesizer(dir + "/v1_cut.pt"),
                    Catch::Contains("v1_cut.pt") && Catch::Contains("refused"));
  fs::remove_all(dir);
}

TEST_CASE("the shipped demo checkpoint still loads", "[unit]") {
  const std::string demo = p2i::testing::SourceDir() + "/models/demo_small_office_64.pt";
  if (!fs::exists(demo)) P2I_SKIP("no " << demo << " (models/ is not in this checkout)");
  auto s = LoadSynthesizer(demo);
  const auto v = s->Render(p2i::scene::Pose::Identity());
  CHECK(v.rgb.cols == 64);
}

TEST_CASE("finite weights whose probe view overflows are refused at load", "[unit]") {
  const auto dir = TempDir("ckpt_probe");
  torch::manual_seed(3);
  Networks n(TinyConfig(), false);
  {
    torch::NoGradGuard g;
    // Finite but huge weights of both signs: products overflow to +-inf in the second layer and
    // their sums become NaN (all of one sign only saturates the output tanh, a finite view).
    for (auto& p : n.Serving()->parameters()) p.normal_().mul_(1e30f);
  }
  CheckpointMeta meta;
  meta.config = TinyConfig();
  meta.normalizer.t_min = {-1, -1, -1};
  meta.normalizer.t_max = {1, 1, 1};
  meta.inference_only = true;
  SaveCheckpoint(dir + "/huge.pt", meta, n, {});
  CHECK_THROWS_WITH(LoadSynthesizer(dir + "/huge.pt"),
                    Catch::Contains("huge.pt") && Catch::Contains("probe view"));
  fs::remove_all(dir);
}

TEST_CASE("p2i export of a torn checkpoint exits non-zero naming it and leaves no .tmp",
          "[integration]") {
  const auto dir = TempDir("ckpt_export_cli");
  const std::string good = ReadFile(TinyInference(dir, "good.pt"));
  WriteBytes(dir + "/torn.pt", Damaged(good, "record"));
  int code = -1;
  const std::string out = p2i::testing::RunCommand(
      p2i::testing::BinDir() + "/p2i export " + dir + "/torn.pt --out " + dir + "/m.pt 2>&1", &code);
  INFO(out);
  CHECK(code == 1);
  CHECK(out.find(dir + "/torn.pt refused") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/m.pt"));
  CHECK_FALSE(AnyTmp(dir));
  fs::remove_all(dir);
}
