/// @file trainer_node_test.cc
/// @brief The p2i_trainer process on an offline capture at 32x32 publishes a ModelVersion that
/// a subscriber receives, and exits 0 on SIGTERM.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <cstdio>
#include <fstream>
#include <thread>

#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "scene/capture.h"
#include "scene/trajectory_io.h"
#include "tests/read_file.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;

namespace {

/// Starts p2i_trainer with `args`, stderr into `err_path`; returns the pid.
pid_t StartTrainer(const std::vector<std::string>& args, const std::string& err_path) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 2);
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

/// Waits up to `limit` for `pid` to exit and stores its wait status; a hang guard, not a timing
/// assertion. False (the child SIGKILLed and reaped) when it did not exit in time.
bool WaitForExit(pid_t pid, std::chrono::seconds limit, int* status) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  pid_t r = 0;
  while (std::chrono::steady_clock::now() < deadline && (r = waitpid(pid, status, WNOHANG)) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  if (r != 0) return true;
  kill(pid, SIGKILL);
  waitpid(pid, status, 0);
  return false;
}

int CountLines(const std::string& path, const std::string& needle) {
  std::ifstream in(path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) n += line.find(needle) != std::string::npos;
  return n;
}

}  // namespace

TEST_CASE("p2i_trainer: offline data at 32x32 publishes a ModelVersion, SIGTERM exits 0",
          "[integration]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir = trainer::testing::TempDir("node");
  const scene::RgbdDataset sim = trainer::testing::SimFrames(16);
  {
    scene::CaptureWriter writer(dir + "/capture", sim.camera);
    for (const auto& f : sim.frames) writer.Append(f);
  }
  {
    std::ofstream(dir + "/tiny.yaml") << trainer::testing::TinyConfig().ToYamlString();
  }

  runtime::Node listener("listener", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  std::vector<msgs::pb::ModelVersion> versions;
  std::vector<msgs::pb::TrainerStatus> statuses;
  listener.Subscribe<msgs::pb::ModelVersion>(
      "/model_version", [&](const msgs::pb::ModelVersion& v) { versions.push_back(v); });
  listener.Subscribe<msgs::pb::TrainerStatus>(
      "/trainer_status", [&](const msgs::pb::TrainerStatus& s) { statuses.push_back(s); });
  listener.Start();

  const std::string exe = p2i::testing::BinDir() + "/p2i_trainer";
  const std::vector<std::string> args = {
      exe, "dataset:=" + dir + "/capture", "config:=" + dir + "/tiny.yaml",
      "work_dir:=" + dir + "/work", "publish_every_steps:=4", "min_frames:=4",
      "max_val_frames:=2", "trainer_status_period:=0.2", "latch_period:=0.2"};
  const std::string err_path = dir + "/stderr.txt";
  const pid_t pid = StartTrainer(args, err_path);
  REQUIRE(pid > 0);
  // A version, and a status that shows the whole capture in the buffer (either may come first).
  const auto got_all = [&] {
    return !versions.empty() && !statuses.empty() && statuses.back().buffer_size() == 16;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(45);
  while (std::chrono::steady_clock::now() < deadline && !got_all())
    listener.SpinOnce(std::chrono::milliseconds(20));
  int status = 0;
  const bool alive = waitpid(pid, &status, WNOHANG) == 0;
  if (!got_all() || !alive) {
    if (alive) kill(pid, SIGKILL), waitpid(pid, &status, 0);
    FAIL("no ModelVersion received; trainer stderr:\n" << p2i::testing::ReadFile(err_path));
  }
  CHECK(versions.front().version() >= 1);
  CHECK(versions.front().width() == 32);
  CHECK(std::filesystem::exists(versions.front().checkpoint_path()));
  // Beside it, the poses it was trained on (for the synthesizer's coverage score): capture
  // poses, all but the held-out validation frames.
  REQUIRE(!versions.front().poses_path().empty());
  const auto trained = scene::ReadTumTrajectory(versions.front().poses_path(),
                                                scene::TumStampOrder::kSort);
  CHECK(trained.size() >= 8);
  CHECK(trained.size() < 16);
  for (const auto& p : trained) {
    bool found = false;
    for (const auto& f : sim.frames)
      found |= (f.pose.translation() - p.pose.translation()).norm() < 1e-6;
    CHECK(found);
  }

  kill(pid, SIGTERM);
  // Generous bound: the test must not depend on timing, only on a clean exit.
  if (!WaitForExit(pid, std::chrono::seconds(20), &status))
    FAIL("p2i_trainer did not exit after SIGTERM");
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::filesystem::remove_all(dir);
}


TEST_CASE("p2i_trainer: SIGTERM inside a long round stops it at a step boundary with a "
          "checkpoint the next start resumes exactly",
          "[integration]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir = trainer::testing::TempDir("stop");
  const scene::RgbdDataset sim = trainer::testing::SimFrames(16);
  {
    scene::CaptureWriter writer(dir + "/capture", sim.camera);
    for (const auto& f : sim.frames) writer.Append(f);
  }
  model::P2iConfig config = trainer::testing::TinyConfig();
  config.checkpoint_every = 100000;  // only the stop hook can save mid-round
  std::ofstream(dir + "/tiny.yaml") << config.ToYamlString();
  const std::string exe = p2i::testing::BinDir() + "/p2i_trainer";
  const std::vector<std::string> common = {exe, "dataset:=" + dir + "/capture",
                                           "config:=" + dir + "/tiny.yaml",
                                           "work_dir:=" + dir + "/work", "min_frames:=4",
                                           "max_val_frames:=2"};

  // A round of 100000 steps: it can only end through the stop hook.
  std::vector<std::string> args = common;
  args.push_back("publish_every_steps:=100000");
  const pid_t pid = StartTrainer(args, dir + "/stderr1.txt");
  REQUIRE(pid > 0);
  const std::string log = dir + "/work/train_log.jsonl";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline && CountLines(log, "\"loss") < 3)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(CountLines(log, "\"loss") >= 3);  // training steps are running
  const auto t0 = std::chrono::steady_clock::now();
  kill(pid, SIGTERM);
  int status = 0;
  const bool exited = WaitForExit(pid, std::chrono::seconds(30), &status);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!exited)
    FAIL("p2i_trainer did not exit after SIGTERM:\n" << p2i::testing::ReadFile(dir + "/stderr1.txt"));
  const std::string err1 = p2i::testing::ReadFile(dir + "/stderr1.txt");
  INFO(err1);
  std::fprintf(stderr, "p2i_trainer: SIGTERM mid-round -> exit after %.2f s\n", seconds);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  // The log names the step it saved at.
  const size_t at = err1.find("training stopped after");
  REQUIRE(at != std::string::npos);
  const size_t step_at = err1.find("at step ", at);
  REQUIRE(step_at != std::string::npos);
  const int saved_step = std::atoi(err1.c_str() + step_at + 8);
  CHECK(saved_step >= 3);
  CHECK(std::filesystem::exists(dir + "/work/checkpoint.pt"));
  CHECK(std::filesystem::is_empty(dir + "/work/versions"));  // the partial round is no version

  // The next start resumes there: its first version is exactly 2 steps later.
  runtime::Node listener("listener", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  std::vector<msgs::pb::ModelVersion> versions;
  listener.Subscribe<msgs::pb::ModelVersion>(
      "/model_version", [&](const msgs::pb::ModelVersion& v) { versions.push_back(v); });
  listener.Start();
  args = common;
  args.push_back("publish_every_steps:=2");
  args.push_back("max_rounds:=1");
  args.push_back("latch_period:=0.2");
  const pid_t pid2 = StartTrainer(args, dir + "/stderr2.txt");
  REQUIRE(pid2 > 0);
  const auto deadline2 = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline2 && versions.empty())
    listener.SpinOnce(std::chrono::milliseconds(20));
  kill(pid2, SIGTERM);
  waitpid(pid2, &status, 0);
  INFO(p2i::testing::ReadFile(dir + "/stderr2.txt"));
  REQUIRE(!versions.empty());
  CHECK(versions.front().version() == 1);
  CHECK(versions.front().step() == static_cast<uint64_t>(saved_step + 2));
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::filesystem::remove_all(dir);
}
