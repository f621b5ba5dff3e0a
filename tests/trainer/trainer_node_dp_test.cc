/// @file trainer_node_dp_test.cc
/// @brief Two p2i_trainer processes as data-parallel ranks (world_size 2, Gloo on 127.0.0.1)
/// fed frames by the test: rank 0 publishes the versions and rank 1 none, both report their
/// rank, each trains on its own shard, every step's gradients were all-reduced on both ranks
/// and each round started from rank 0's checkpoint; rank 1 SIGKILLed mid-run ends rank 0's
/// training with "lost contact" in its TrainerStatus and leaves its last version loadable; a
/// rank stopped (SIGTERM) between rounds or mid-run ends the other's training cleanly, in
/// phase "stopped" with which rank stopped it, not "lost contact".
#include <catch2/catch.hpp>

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "tests/read_file.h"
#include "tests/process_util.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;
namespace fs = std::filesystem;

namespace {

/// A master port of this test process (k: one per test case).
std::string Port(int k) { return std::to_string(33000 + (::getpid() * 11 + k) % 20000); }

/// The test as camera: publishes `sim`'s frames in turn on /rgbd (inline camera_info, posed),
/// and listens to both ranks' model_version and trainer_status (rank 1 in namespace /rank1).
class Harness {
 public:
  explicit Harness(const scene::RgbdDataset& sim)
      : sim_(sim), node_("dp_test", runtime::NodeArgs::Parse(std::vector<std::string>{})) {
    pub_ = node_.Advertise<msgs::RgbdFrame>("/rgbd");
    for (const std::string ns : {"", "/rank1"}) {
      const int rank = ns.empty() ? 0 : 1;
      node_.Subscribe<msgs::pb::ModelVersion>(
          ns + "/model_version",
          [this, rank](const msgs::pb::ModelVersion& v) { versions_[rank].push_back(v); });
      node_.Subscribe<msgs::pb::TrainerStatus>(
          ns + "/trainer_status",
          [this, rank](const msgs::pb::TrainerStatus& s) { status_[rank] = s; });
    }
    node_.Start();
  }

  /// Publishes a frame every ~20 ms and spins until `done()` or `limit` (a hang guard).
  bool RunUntil(const std::function<bool()>& done, std::chrono::seconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline && !done()) {
      const auto& f = sim_.frames[next_++ % sim_.frames.size()];
      msgs::RgbdFrame m;
      convert::ToMsg(sim_.camera, m.meta.mutable_camera_info());
      convert::ToMsg(f.pose, m.meta.mutable_pose());
      m.rgb = convert::ToImage(f.rgb);
      m.depth = convert::ToImage(f.depth);
      pub_->Publish(m);
      for (int k = 0; k < 10; ++k) node_.SpinOnce(std::chrono::milliseconds(2));
    }
    return done();
  }

  /// Spins without publishing frames until `done()` or `limit`.
  bool SpinUntil(const std::function<bool()>& done, std::chrono::seconds limit) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    while (std::chrono::steady_clock::now() < deadline && !done())
      node_.SpinOnce(std::chrono::milliseconds(20));
    return done();
  }

  const std::vector<msgs::pb::ModelVersion>& Versions(int rank) { return versions_[rank]; }
  /// The newest TrainerStatus of `rank` (phase "" before the first).
  msgs::pb::TrainerStatus Status(int rank) { return status_[rank]; }
  uint64_t HighestVersion(int rank) {
    uint64_t v = 0;
    for (const auto& m : versions_[rank]) v = std::max<uint64_t>(v, m.version());
    return v;
  }

 private:
  const scene::RgbdDataset& sim_;
  runtime::Node node_;
  std::shared_ptr<runtime::Publisher<msgs::RgbdFrame>> pub_;
  std::map<int, std::vector<msgs::pb::ModelVersion>> versions_;
  std::map<int, msgs::pb::TrainerStatus> status_;
  size_t next_ = 0;
};

/// p2i_trainer as rank `rank` of 2 (rank 1 in namespace /rank1, subscribed to /rgbd), stderr
/// into DIR/rank<R>.log, work dir DIR/r<R>.
std::unique_ptr<p2i::testing::Process> StartRank(const std::string& dir, int rank,
                                                 const std::string& port,
                                                 const std::string& extra) {
  const std::string r = std::to_string(rank);
  std::string cmd = "exec '" + p2i::testing::BinDir() + "/p2i_trainer'";
  if (rank > 0) cmd += " --namespace /rank" + r + " -r rgbd:=/rgbd";
  cmd += " config:=" + dir + "/tiny.yaml work_dir:=" + dir + "/r" + r +
         " world_size:=2 rank:=" + r + " master:=127.0.0.1:" + port +
         " dist_timeout:=30 publish_every_steps:=3 enet_steps_per_version:=0 min_frames:=4"
         " max_val_frames:=2 buffer_mb:=4 threads:=1 trainer_status_period:=0.2"
         " latch_period:=0.2 " + extra + " 2> '" + dir + "/rank" + r + ".log'";
  return std::make_unique<p2i::testing::Process>(
      std::vector<std::string>{"/bin/sh", "-c", cmd});
}

/// Index of the frame of `sim` at translation (x, y, z), or -1.
int FrameAt(const scene::RgbdDataset& sim, double x, double y, double z) {
  for (size_t i = 0; i < sim.frames.size(); ++i)
    if ((sim.frames[i].pose.translation() - Eigen::Vector3d(x, y, z)).norm() < 1e-6)
      return static_cast<int>(i);
  return -1;
}

/// The frames of `sim` a TUM poses file names (by translation; -1 for an unknown pose).
std::set<int> FramesOf(const scene::RgbdDataset& sim, const std::string& poses_path) {
  std::set<int> frames;
  std::istringstream in(p2i::testing::ReadFile(poses_path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double stamp = 0, x = 0, y = 0, z = 0;
    ls >> stamp >> x >> y >> z;
    frames.insert(FrameAt(sim, x, y, z));
  }
  return frames;
}

/// The set-up every two-rank scenario below shares: a fresh shutdown flag and run directory, a
/// work folder `dir` with the tiny config, 16 sim frames and the harness that publishes them, and
/// ranks 0 and 1 started on this test case's master port (Port(port_index)) with `extra`.
struct TwoRanks {
  TwoRanks(const std::string& name, int port_index, const std::string& extra)
      : reset_((runtime::Shutdown::ResetForTesting(), 0)),
        dir(trainer::testing::TempDir(name)),
        config(trainer::testing::TinyConfig()),
        sim(trainer::testing::SimFrames(16)),
        h(sim) {
    std::ofstream(dir + "/tiny.yaml") << config.ToYamlString();
    const std::string port = Port(port_index);
    r0 = StartRank(dir, 0, port, extra);
    r1 = StartRank(dir, 1, port, extra);
  }
  /// Both ranks' logs (stderr), for INFO.
  std::string Logs() const {
    return "rank 0:\n" + p2i::testing::ReadFile(dir + "/rank0.log") + "\nrank 1:\n" +
           p2i::testing::ReadFile(dir + "/rank1.log");
  }

 private:
  int reset_;  // Shutdown::ResetForTesting, before anything else is built

 public:
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir;
  const model::P2iConfig config;
  const scene::RgbdDataset sim;
  Harness h;
  std::unique_ptr<p2i::testing::Process> r0, r1;
};

}  // namespace

TEST_CASE("p2i_trainer world_size 2: rank 0 publishes the versions both ranks trained, each on "
          "its own shard, every step all-reduced",
          "[integration]") {
  TwoRanks t("dp", 0, "max_rounds:=2");
  const bool done = t.h.RunUntil(
      [&] {
        return t.h.Status(0).phase() == "done" && t.h.Status(1).phase() == "done" &&
               t.h.HighestVersion(0) == 2;
      },
      std::chrono::seconds(120));
  INFO(t.Logs());
  REQUIRE(done);
  for (int rank : {0, 1}) {
    const auto s = t.h.Status(rank);
    CHECK(s.world_size() == 2);
    CHECK(s.rank() == static_cast<uint32_t>(rank));
    CHECK(s.error().empty());
    CHECK(s.step() == 6);  // two rounds of 3 steps on every rank
  }
  // Only rank 0 publishes and writes versions.
  CHECK(t.h.Versions(1).empty());
  CHECK((!fs::exists(t.dir + "/r1/versions") || fs::is_empty(t.dir + "/r1/versions")));
  const auto& v = t.h.Versions(0).back();
  CHECK(v.step() == 6);
  REQUIRE(fs::exists(v.checkpoint_path()));

  // Every phase-1 step all-reduced D's and G's gradients on both ranks (d_steps + 1 per step).
  const auto stats0 = nlohmann::json::parse(p2i::testing::ReadFile(t.dir + "/r0/distributed.rank0.json"));
  const auto stats1 = nlohmann::json::parse(p2i::testing::ReadFile(t.dir + "/r1/distributed.rank1.json"));
  const int per_step = t.config.d_steps + 1;
  CHECK(stats0["allreduce_calls"].get<int>() == 6 * per_step);
  CHECK(stats1["allreduce_calls"].get<int>() == 6 * per_step);
  CHECK(stats0["allreduce_sizes_bytes"] == stats1["allreduce_sizes_bytes"]);
  CHECK(stats0["allreduce_sizes_bytes"].size() == 2);  // D's and G's gradients

  // The second round started on rank 1 from rank 0's checkpoint of version 1 (the same bytes).
  const std::string v1 = t.dir + "/r0/versions/model_v000001.pt";
  REQUIRE(fs::exists(v1));
  CHECK(p2i::testing::ReadFile(t.dir + "/r1/checkpoint.pt") == p2i::testing::ReadFile(v1));

  // Shards: frames are published in turn, so each rank's seq % 2 keeps every other one of the
  // 16 sim frames: the poses rank 0 trained on are all of one parity.
  const std::set<int> frames = FramesOf(t.sim, v.poses_path());
  CHECK(frames.count(-1) == 0);
  CHECK(frames.size() >= 3);
  std::set<int> parities;
  for (int f : frames) parities.insert(f % 2);
  CHECK(parities.size() == 1);

  CHECK(t.r0->Terminate() == 0);
  CHECK(t.r1->Terminate() == 0);
  fs::remove_all(t.dir);
}

TEST_CASE("p2i_trainer world_size 2: rank 1 SIGKILLed mid-run ends rank 0's training with "
          "'lost contact' in its TrainerStatus, and the last version loads",
          "[integration]") {
  TwoRanks t("dp_kill", 1, "");
  const bool trained =
      t.h.RunUntil([&] { return t.h.HighestVersion(0) >= 2; }, std::chrono::seconds(120));
  INFO(t.Logs());
  REQUIRE(trained);
  ::kill(t.r1->pid(), SIGKILL);
  CHECK(t.r1->Wait() == -SIGKILL);
  const bool ended = t.h.RunUntil([&] { return t.h.Status(0).phase() == "error"; },
                                std::chrono::seconds(60));
  INFO("rank 0 after the kill:\n" << p2i::testing::ReadFile(t.dir + "/rank0.log"));
  REQUIRE(ended);
  const auto s = t.h.Status(0);
  CHECK(s.error().find("lost contact with the other ranks") != std::string::npos);
  CHECK(s.rank() == 0);
  CHECK(s.world_size() == 2);

  // The newest version rank 0 published is whole: a tool loads it.
  const uint64_t last = t.h.HighestVersion(0);
  std::string path;
  for (const auto& v : t.h.Versions(0))
    if (v.version() == last) path = v.checkpoint_path();
  REQUIRE(fs::exists(path));
  int code = -1;
  const std::string out = p2i::testing::RunCommand(
      "'" + p2i::testing::BinDir() + "/p2i' export '" + path + "' --out '" + t.dir +
          "/exported.pt' 2>&1",
      &code);
  INFO(out);
  CHECK(code == 0);
  CHECK(fs::exists(t.dir + "/exported.pt"));
  CHECK(t.r0->Terminate() == 0);  // the node outlives its training's end and stops cleanly
  fs::remove_all(t.dir);
}

TEST_CASE("p2i_trainer world_size 2: rank 1 stopped between rounds ends rank 0's training "
          "cleanly, with a stop message instead of 'lost contact'",
          "[integration]") {
  TwoRanks t("dp_stop", 2, "");
  // No frames: both ranks met (the first poll is the rendezvous) and wait between rounds.
  const bool waiting = t.h.SpinUntil(
      [&] { return t.h.Status(0).phase() == "waiting" && t.h.Status(1).phase() == "waiting"; },
      std::chrono::seconds(60));
  INFO(t.Logs());
  REQUIRE(waiting);
  CHECK(t.r1->Terminate() == 0);  // SIGTERM: the node's shutdown
  // Well within dist_timeout (30 s): rank 0 learns it at the next poll, not by a timeout.
  const bool ended = t.h.SpinUntil([&] { return t.h.Status(0).phase() == "stopped"; },
                                 std::chrono::seconds(15));
  INFO("rank 0 after rank 1's stop:\n" << p2i::testing::ReadFile(t.dir + "/rank0.log"));
  REQUIRE(ended);
  const auto s = t.h.Status(0);
  CHECK(s.error().find("rank 1 was stopped (its node shut down) between rounds") !=
        std::string::npos);
  CHECK(s.error().find("lost contact") == std::string::npos);
  CHECK(p2i::testing::ReadFile(t.dir + "/rank0.log").find("rank 1 was stopped") !=
        std::string::npos);  // the node logs why its training ended
  CHECK(t.r0->Terminate() == 0);
  fs::remove_all(t.dir);
}

TEST_CASE("p2i_trainer world_size 2: rank 0 stopped mid-run ends rank 1's training cleanly, and "
          "rank 0's checkpoint loads",
          "[integration]") {
  TwoRanks t("dp_stop_run", 3, "");
  const bool trained =
      t.h.RunUntil([&] { return t.h.HighestVersion(0) >= 2; }, std::chrono::seconds(120));
  INFO(t.Logs());
  REQUIRE(trained);
  // During a round (the per-step stop flag) or between rounds (the poll): either way clean.
  CHECK(t.r0->Terminate() == 0);
  const bool ended = t.h.SpinUntil([&] { return t.h.Status(1).phase() == "stopped"; },
                                 std::chrono::seconds(15));
  INFO("rank 1 after rank 0's stop:\n" << p2i::testing::ReadFile(t.dir + "/rank1.log"));
  REQUIRE(ended);
  const auto s = t.h.Status(1);
  CHECK((s.error().find("rank 0 was stopped") != std::string::npos ||
         s.error().find("another rank was stopped during a round") != std::string::npos));
  CHECK(s.error().find("lost contact") == std::string::npos);
  int code = -1;
  const std::string out = p2i::testing::RunCommand(
      "'" + p2i::testing::BinDir() + "/p2i' export '" + t.dir + "/r0/checkpoint.pt' --out '" +
          t.dir + "/exported.pt' 2>&1",
      &code);
  INFO(out);
  CHECK(code == 0);
  CHECK(t.r1->Terminate() == 0);
  fs::remove_all(t.dir);
}
