/// @file distributed_test.cc
/// @brief Data-parallel `p2i train` on Gloo over loopback: two ranks give the weights of one
/// rank with the doubled batch, also through a divergence rollback forced on one rank only; a
/// rank killed mid-run stops the other with a clear error and an intact checkpoint, from which
/// every rank resumes; a fresh start's pose normaliser is that of every rank's frames, and its
/// `fourier_bands: auto` count rank 0's.
#include <signal.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include "model/checkpoint.h"
#include "model/distributed.h"
#include "model/networks.h"
#include "tests/model/model_test_util.h"
#include "tests/process_util.h"
#include "tests/read_file.h"
#include "tests/test_paths.h"

using namespace p2i::model;
using namespace p2i::model::testing;
namespace fs = std::filesystem;

using p2i::testing::ReadFile;

namespace {

std::string Port() { return std::to_string(30000 + (::getpid() * 7) % 20000); }

/// `p2i train` through the shell (output in `log`); `exec` keeps the pid the trainer's.
std::unique_ptr<p2i::testing::Process> Train(const std::string& args, const std::string& log) {
  const std::string cmd = "exec '" + p2i::testing::BinDir() + "/p2i' train " + args + " > '" +
                          log + "' 2>&1";
  return std::make_unique<p2i::testing::Process>(std::vector<std::string>{"/bin/sh", "-c", cmd});
}

/// Mean absolute difference of G's parameters in two checkpoints (the largest over tensors).
double GDifference(const P2iConfig& config, const std::string& a, const std::string& b) {
  Networks na(config), nb(config);
  LoadCheckpoint(a, na, {}, false);
  LoadCheckpoint(b, nb, {}, false);
  auto pa = na.g->parameters(), pb = nb.g->parameters();
  REQUIRE(pa.size() == pb.size());
  double worst = 0;
  for (size_t i = 0; i < pa.size(); ++i)
    worst = std::max(worst, (pa[i] - pb[i]).abs().mean().item<double>());
  return worst;
}

/// Two data-parallel ranks as threads of this process, rank r training on shard[r] for
/// `steps` phase-1 steps into DIR/r<r> (master port Port() + `port_offset`); each rank's error
/// message, empty when it finished.
std::array<std::string, 2> TrainTwoRanksInProcess(const P2iConfig& c,
                                                  const p2i::scene::RgbdDataset shard[2],
                                                  const std::string& dir, int port_offset,
                                                  int steps) {
  DistributedOptions d;
  d.world_size = 2;
  d.master = "127.0.0.1:" + std::to_string(std::stoi(Port()) + port_offset);
  d.timeout_s = 30;
  std::array<std::string, 2> errors;
  auto run = [&](int r) {
    try {
      TrainerOptions o;
      o.out_dir = dir + "/r" + std::to_string(r);
      o.phase = 1;
      o.steps = steps;
      o.threads = 1;
      o.progress = false;
      o.distributed = d;
      o.distributed.rank = r;
      Trainer(c, o).Run(shard[r], p2i::scene::RgbdDataset{});
    } catch (const std::exception& e) {
      errors[r] = e.what();
    }
  };
  std::thread rank1(run, 1);
  run(0);
  rank1.join();
  return errors;
}

}  // namespace

TEST_CASE("DistributedOptions: bad ranks, masters and timeouts are named", "[unit]") {
  DistributedOptions o;
  o.Validate();  // one process
  o.world_size = 2;
  o.rank = 2;
  o.master = "127.0.0.1:29500";
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("--rank 2 must be in 0..1"));
  o.rank = 1;
  o.master = "127.0.0.1";
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("must be HOST:PORT"));
  o.master = "127.0.0.1:29500";
  o.timeout_s = 0;
  CHECK_THROWS_WITH(o.Validate(), Catch::Contains("--dist-timeout"));
}

TEST_CASE("Two Gloo ranks on loopback give the weights of one rank with the doubled batch",
          "[integration]") {
  const auto dir = TempDir("dp_equal");
  P2iConfig c = TinyConfig("cnn_baseline");
  c.checkpoint_every = 100;
  std::ofstream(dir + "/b4.yaml") << c.ToYamlString();
  P2iConfig c8 = c;
  c8.batch_size = 8;
  std::ofstream(dir + "/b8.yaml") << c8.ToYamlString();
  const std::string common = " --data procedural --frames 16 --phase 1 --steps 5 --threads 1 --quiet";
  int code = -1;
  const std::string one = p2i::testing::RunCommand(
      p2i::testing::BinDir() + "/p2i train " + dir + "/b8.yaml" + common + " --out " + dir +
          "/one 2>&1", &code);
  INFO(one);
  REQUIRE(code == 0);
  p2i::testing::RunCommand(p2i::testing::BinDir() + "/p2i train " + dir + "/b4.yaml" + common +
                               " --out " + dir + "/single4 2>&1", &code);
  REQUIRE(code == 0);

  const std::string dist = dir + "/b4.yaml" + common + " --out " + dir +
                           "/two --world-size 2 --master 127.0.0.1:" + Port() +
                           " --dist-timeout 60 --rank ";
  auto r0 = Train(dist + "0", dir + "/rank0.log");
  auto r1 = Train(dist + "1", dir + "/rank1.log");
  const int c0 = r0->Wait(), c1 = r1->Wait();
  INFO(ReadFile(dir + "/rank0.log") << ReadFile(dir + "/rank1.log"));
  REQUIRE(c0 == 0);
  REQUIRE(c1 == 0);
  CHECK(ReadCheckpointMeta(dir + "/two/checkpoint.pt").phase1_step == 5);
  CHECK(fs::exists(dir + "/two/train_log.rank1.jsonl"));  // rank 1 logs, never checkpoints

  const double same = GDifference(c, dir + "/one/checkpoint.pt", dir + "/two/checkpoint.pt");
  const double other = GDifference(c, dir + "/single4/checkpoint.pt", dir + "/two/checkpoint.pt");
  INFO("two ranks vs doubled batch " << same << ", vs one rank with the single batch " << other);
  CHECK(same < 1e-6);
  CHECK(other > 100 * std::max(same, 1e-9));  // the comparison can tell batches apart

  // Every all-reduce carried all of G's gradients as float32, and the divergence flag.
  Networks n(c);
  int64_t numel = 0;
  for (const auto& p : n.g->parameters()) numel += p.numel();
  const auto stats = nlohmann::json::parse(ReadFile(dir + "/two/distributed.rank0.json"));
  CHECK(stats["bytes_per_allreduce"].get<int64_t>() == 4 * (numel + 1));
  CHECK(stats["allreduce_calls"].get<int>() == 5);
  fs::remove_all(dir);
}

TEST_CASE("A rank killed mid-run stops the other with a clear error, and both resume from rank 0's "
          "intact checkpoint",
          "[integration]") {
  const auto dir = TempDir("dp_kill");
  P2iConfig c = TinyConfig("cnn_baseline");
  c.checkpoint_every = 5;
  std::ofstream(dir + "/tiny.yaml") << c.ToYamlString();
  const std::string port = std::to_string(std::stoi(Port()) + 1);
  const std::string common = dir + "/tiny.yaml --data procedural --frames 16 --phase 1 "
                             "--threads 1 --quiet --out " + dir + "/run --world-size 2 "
                             "--master 127.0.0.1:" + port + " --dist-timeout 20";
  auto r0 = Train(common + " --steps 1000000 --rank 0", dir + "/rank0.log");
  auto r1 = Train(common + " --steps 1000000 --rank 1", dir + "/rank1.log");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (ReadFile(dir + "/run/train_log.jsonl").find("\"step\":20") == std::string::npos &&
         std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  REQUIRE(ReadFile(dir + "/run/train_log.jsonl").find("\"step\":20") != std::string::npos);
  ::kill(r1->pid(), SIGKILL);
  CHECK(r1->Wait() == -SIGKILL);
  const int c0 = r0->Wait();  // no hang: the dead peer's connection fails the all-reduce
  const std::string log0 = ReadFile(dir + "/rank0.log");
  INFO(log0);
  CHECK(c0 != 0);
  CHECK(log0.find("lost contact with the other ranks") != std::string::npos);
  CHECK(log0.find("--resume") != std::string::npos);

  // The checkpoint is whole (written atomically by rank 0) and every rank resumes from it.
  const CheckpointMeta meta = ReadCheckpointMeta(dir + "/run/checkpoint.pt");
  CHECK(meta.phase1_step >= 20);
  Networks n(c);
  CHECK_NOTHROW(LoadCheckpoint(dir + "/run/checkpoint.pt", n, {}, false));
  const std::string to = " --steps " + std::to_string(meta.phase1_step + 3) + " --resume --rank ";
  auto q0 = Train(common + to + "0", dir + "/resume0.log");
  auto q1 = Train(common + to + "1", dir + "/resume1.log");
  const int e0 = q0->Wait(), e1 = q1->Wait();
  INFO(ReadFile(dir + "/resume0.log") << ReadFile(dir + "/resume1.log"));
  CHECK(e0 == 0);
  CHECK(e1 == 0);
  CHECK(ReadCheckpointMeta(dir + "/run/checkpoint.pt").phase1_step == meta.phase1_step + 3);
  fs::remove_all(dir);
}

TEST_CASE("A divergence on one rank rolls back every rank: a NaN forced on rank 1 only gives the "
          "weights of one rank with the doubled batch and the same NaN",
          "[integration]") {
  const auto dir = TempDir("dp_rollback");
  P2iConfig c = TinyConfig("cnn_baseline");
  c.checkpoint_every = 100;  // the rollback goes back to step 0 (the run's first checkpoint)
  std::ofstream(dir + "/b4.yaml") << c.ToYamlString();
  P2iConfig c8 = c;
  c8.batch_size = 8;
  std::ofstream(dir + "/b8.yaml") << c8.ToYamlString();
  const std::string common =
      " --data procedural --frames 16 --phase 1 --steps 6 --threads 1 --quiet";
  int code = -1;
  const std::string one = p2i::testing::RunCommand(
      p2i::testing::BinDir() + "/p2i train " + dir + "/b8.yaml" + common +
          " --inject-nan-at-step 3 --out " + dir + "/one 2>&1", &code);
  INFO(one);
  REQUIRE(code == 0);
  const std::string dist = dir + "/b4.yaml" + common + " --out " + dir +
                           "/two --world-size 2 --master 127.0.0.1:" +
                           std::to_string(std::stoi(Port()) + 2) + " --dist-timeout 30 --rank ";
  auto r0 = Train(dist + "0", dir + "/rank0.log");
  auto r1 = Train(dist + "1 --inject-nan-at-step 3", dir + "/rank1.log");  // rank 1 only
  const int c0 = r0->Wait(), c1 = r1->Wait();
  INFO(ReadFile(dir + "/rank0.log") << ReadFile(dir + "/rank1.log"));
  REQUIRE(c0 == 0);
  REQUIRE(c1 == 0);

  // Both ranks rolled back at step 3 (rank 0 on rank 1's word) and halved the learning rate.
  const std::string log0 = ReadFile(dir + "/two/train_log.jsonl");
  const std::string log1 = ReadFile(dir + "/two/train_log.rank1.jsonl");
  INFO(log0 << log1);
  CHECK(log0.find("\"event\":\"rollback\"") != std::string::npos);
  CHECK(log0.find("a loss diverged on another rank") != std::string::npos);
  CHECK(log1.find("\"event\":\"rollback\"") != std::string::npos);
  CHECK(log1.find("L2 loss is not finite") != std::string::npos);
  const CheckpointMeta meta = ReadCheckpointMeta(dir + "/two/checkpoint.pt");
  CHECK(meta.phase1_step == 6);
  CHECK(meta.rollbacks == 1);
  CHECK(meta.lr_scale == Approx(0.5));
  CHECK(ReadCheckpointMeta(dir + "/one/checkpoint.pt").rollbacks == 1);
  CHECK_FALSE(fs::exists(dir + "/two/rollback.rank1.pt"));  // rank 1's copy of rank 0's file

  // The same weights as one process with the doubled batch through the same rollback.
  const double same = GDifference(c, dir + "/one/checkpoint.pt", dir + "/two/checkpoint.pt");
  INFO("two ranks with the rollback vs the doubled batch with it: " << same);
  CHECK(same < 1e-6);
  fs::remove_all(dir);
}

TEST_CASE("A data-parallel fresh start's pose normaliser is that of every rank's frames",
          "[integration]") {
  // The trainer node's ranks hold disjoint shards: rank 1's frames here lie 10 m further
  // along x than rank 0's, so rank 0's own bounds would miss all of them.
  const auto dir = TempDir("dp_normaliser");
  const P2iConfig c = TinyConfig("cnn_baseline");
  p2i::scene::RgbdDataset shard[2];
  std::vector<std::array<double, 7>> all;
  for (int r = 0; r < 2; ++r) {
    shard[r] = MakeProceduralDataset(6, 32, static_cast<uint64_t>(r));
    for (auto& f : shard[r].frames) {
      f.pose = p2i::scene::Pose(f.pose.translation() + Eigen::Vector3d(10.0 * r, 0, 0),
                                f.pose.rotation());
      const auto v = f.pose.ToVector7();
      all.push_back({v[0], v[1], v[2], v[3], v[4], v[5], v[6]});
    }
  }
  const auto errors = TrainTwoRanksInProcess(c, shard, dir, 3, 0);
  INFO(errors[0] << " / " << errors[1]);
  REQUIRE(errors[0].empty());
  REQUIRE(errors[1].empty());
  const PoseNormalizer got = ReadCheckpointMeta(dir + "/r0/checkpoint.pt").normalizer;
  const PoseNormalizer want = PoseNormalizer::FromPoses(all);
  const PoseNormalizer rank0_only =
      PoseNormalizer::FromPoses(std::vector<std::array<double, 7>>(all.begin(), all.begin() + 6));
  for (int a = 0; a < 3; ++a) {
    CHECK(got.t_min[a] == Approx(want.t_min[a]).margin(1e-12));
    CHECK(got.t_max[a] == Approx(want.t_max[a]).margin(1e-12));
  }
  CHECK(got.t_max[0] > rank0_only.t_max[0] + 5.0);  // the test tells the two apart
  fs::remove_all(dir);
}

TEST_CASE("A data-parallel fresh start with fourier_bands: auto builds rank 0's count everywhere",
          "[integration]") {
  // Disjoint shards of different density: on its own rank 0's 8 frames call for 2 bands and
  // rank 1's 32 for 4 (tests/model/trainer_test.cc). Ranks that chose for themselves would
  // build Gs of different input widths, and the start's weight broadcast would fail.
  const auto dir = TempDir("dp_auto_bands");
  const P2iConfig c = AutoFourierBandsConfig(TinyConfig("cnn_baseline"));
  const p2i::scene::RgbdDataset shard[2] = {FramesOnALine(8, 0), FramesOnALine(32, 0)};
  const auto errors = TrainTwoRanksInProcess(c, shard, dir, 4, 1);
  INFO(errors[0] << " / " << errors[1]);
  REQUIRE(errors[0].empty());
  REQUIRE(errors[1].empty());
  CHECK(ReadCheckpointMeta(dir + "/r0/checkpoint.pt").config.fourier_bands == 2);
  for (const std::string& log : {dir + "/r0/train_log.jsonl", dir + "/r1/train_log.rank1.jsonl"}) {
    INFO(log);
    CHECK(StartEvent(log).at("fourier_bands") == 2);
  }
  fs::remove_all(dir);
}
