/// @file train_cli_stop_test.cc
/// @brief `p2i train` stopped by SIGTERM mid-run: exits 0 with a checkpoint at the current step
/// (the Trainer's stop hook), and --resume continues from it.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "tests/model/model_test_util.h"
#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using namespace p2i::model;
using namespace p2i::model::testing;

using p2i::testing::ReadFile;

TEST_CASE("p2i train stops on SIGTERM with a checkpoint at the current step", "[integration]") {
  const auto dir = TempDir("train_stop");
  const std::string config = dir + "/tiny.yaml";
  std::ofstream(config) << TinyConfig().ToYamlString();
  const std::string p2i = p2i::testing::BinDir() + "/p2i";
  const std::string log = dir + "/run/train_log.jsonl";
  {
    p2i::testing::Process train({p2i, "train", config, "--data", "procedural", "--frames", "16",
                                 "--out", dir + "/run", "--phase", "1", "--steps", "1000000",
                                 "--threads", "1", "--quiet"});
    REQUIRE(train.pid() > 0);
    // Wait until it has trained a few steps (a loss line every 10 steps).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(50);
    while (ReadFile(log).find("\"step\":10") == std::string::npos &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    REQUIRE(ReadFile(log).find("\"step\":10") != std::string::npos);
    CHECK(train.Terminate() == 0);  // SIGTERM: stop hook, checkpoint, normal exit
  }
  const std::string text = ReadFile(log);
  CHECK(text.find("\"event\":\"stopped\"") != std::string::npos);
  const auto meta = ReadCheckpointMeta(dir + "/run/checkpoint.pt");
  CHECK(meta.phase1_step >= 10);
  CHECK(meta.phase1_step < 1000000);
  // --resume continues from the stopped step.
  int code = -1;
  const std::string out = p2i::testing::RunCommand(
      p2i + " train " + config + " --data procedural --frames 16 --out " + dir + "/run --phase 1 --steps " +
          std::to_string(meta.phase1_step + 2) + " --threads 1 --quiet --resume 2>&1",
      &code);
  INFO(out);
  CHECK(code == 0);
  CHECK(ReadCheckpointMeta(dir + "/run/checkpoint.pt").phase1_step == meta.phase1_step + 2);
  fs::remove_all(dir);
}

TEST_CASE("p2i train adds the densified views its config or --set asks for and names a bad --set key",
          "[integration]") {
  const auto dir = TempDir("train_densify");
  P2iConfig c = TinyConfig();
  const std::string plain = dir + "/tiny.yaml";  // densify_ratio 0
  std::ofstream(plain) << c.ToYamlString();
  c.densify_ratio = 0.5;
  c.densify_method = "warp";
  const std::string densify = dir + "/tiny_densify.yaml";
  std::ofstream(densify) << c.ToYamlString();
  const std::string p2i = p2i::testing::BinDir() + "/p2i";
  // 16 procedural frames, every 10th (5 and 15) held out: 14 train, 7 views added. The --set
  // options come before the positional config: each takes one value.
  const std::vector<std::string> ways = {
      densify, "--set densify_ratio=0.5 --set densify_method=warp " + plain};
  for (size_t i = 0; i < ways.size(); ++i) {
    const std::string run = dir + "/run" + std::to_string(i);
    int code = -1;
    const std::string out = p2i::testing::RunCommand(
        p2i + " train " + ways[i] + " --data procedural --frames 16 --out " + run +
            " --phase 1 --steps 1 --threads 1 --quiet 2>&1",
        &code);
    INFO(ways[i] << "\n" << out);
    CHECK(code == 0);
    CHECK(out.find("densified: 7 views of warp") != std::string::npos);
    CHECK(ReadFile(run + "/train_log.jsonl").find("\"train_frames\":21") != std::string::npos);
  }
  int bad_code = -1;
  const std::string bad = p2i::testing::RunCommand(
      p2i + " train " + plain + " --set densify_raito=1 --data procedural --frames 16 --out " +
          dir + "/bad --steps 1 --threads 1 --quiet 2>&1",
      &bad_code);
  INFO(bad);
  CHECK(bad_code != 0);
  CHECK(bad.find("unknown key 'densify_raito'") != std::string::npos);
  CHECK(bad.find("--set densify_raito=1") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/bad/checkpoint.pt"));
  fs::remove_all(dir);
}
