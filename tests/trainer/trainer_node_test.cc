/// @file trainer_node_test.cc
/// @brief The p2i_trainer process on an offline capture at 32x32 publishes a ModelVersion that
/// a subscriber receives, and exits 0 on SIGTERM.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "scene/capture.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;

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
    std::ifstream in(err_path);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    FAIL("no ModelVersion received; trainer stderr:\n" << text);
  }
  CHECK(versions.front().version() >= 1);
  CHECK(versions.front().width() == 32);
  CHECK(std::filesystem::exists(versions.front().checkpoint_path()));

  kill(pid, SIGTERM);
  // Generous bound: the test must not depend on timing, only on a clean exit.
  const auto stop_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  pid_t r = 0;
  while (std::chrono::steady_clock::now() < stop_deadline &&
         (r = waitpid(pid, &status, WNOHANG)) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (r == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    FAIL("p2i_trainer did not exit after SIGTERM");
  }
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  std::filesystem::remove_all(dir);
}
