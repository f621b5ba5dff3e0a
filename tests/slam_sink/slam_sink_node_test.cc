/// @file slam_sink_node_test.cc
/// @brief p2i_slam_sink as a process: views published from the test end up as a TUM sequence,
/// with the lost seq reported and everything acknowledged on disk after SIGTERM.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <set>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "nodes/slam_sink/message_conversion.h"
#include "tests/read_file.h"
#include "tests/slam_sink/sink_test_util.h"
#include "tests/test_paths.h"

namespace p2i::slam_sink {
namespace {

using testing::BasePose;
using testing::DataLines;
using testing::Moved;
using testing::RenderedFrame;
using testing::SmallCamera;
using testing::Split;
using testing::TempDir;

msgs::View ToView(const SinkFrame& f) {
  msgs::View view;
  view.meta.mutable_header()->set_capture_stamp_ns(static_cast<int64_t>(f.stamp * 1e9));
  view.meta.mutable_header()->set_frame_id("world");
  convert::ToMsg(f.pose, view.meta.mutable_pose());
  view.meta.set_coverage(f.coverage);
  view.meta.set_model_version(3);
  view.meta.set_method("sim");
  view.rgb = convert::ToImage(f.rgb);
  view.depth = convert::ToImage(f.depth);
  return view;
}

runtime::NodeArgs Args(const std::vector<std::string>& a) { return runtime::NodeArgs::Parse(a); }

// long-function: one scenario on one sink process: views in (one lost), SIGTERM, flush;
// the files and the loss report checked at the end are what the steps before sent.
TEST_CASE("p2i_slam_sink writes published views, reports the lost one, flushes on SIGTERM",
          "[integration]") {
  runtime::Shutdown::ResetForTesting();
  TempDir run_dir("run");
  TempDir out("node_out");
  setenv("P2I_RUN_DIR", run_dir.path().c_str(), 1);
  const std::string camera_file = run_dir.path() + "/camera.yaml";
  SmallCamera().ToYamlFile(camera_file);
  const std::string out_dir = out.path() + "/seq";

  const std::string exe = p2i::testing::BinDir() + "/p2i_slam_sink";
  const std::string err_path = run_dir.path() + "/sink_stderr.txt";
  std::vector<std::string> args = {exe, "out_dir:=" + out_dir, "camera_info_file:=" + camera_file,
                                   "status_period:=0.05", "policy:=flag", "summary_period:=0"};
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const int fd = open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  // Never leave the sink running when an assertion ends the test early.
  struct Reaper {
    pid_t pid;
    bool reaped = false;
    ~Reaper() {
      if (!reaped) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
      }
      unsetenv("P2I_RUN_DIR");
    }
  } reaper{pid};
  auto stderr_text = [&] { return p2i::testing::ReadFile(err_path); };

  runtime::Node test("sink_test", Args({}));
  auto pub = test.Advertise<msgs::View>("views");
  uint64_t views_received = 0;
  test.Subscribe<msgs::pb::NodeStatus>("/slam_sink/status", [&](const msgs::pb::NodeStatus& s) {
    const auto it = s.counters().find("views_received");
    if (it != s.counters().end()) views_received = it->second;
  });
  test.Start();
  auto spin_for = [&](std::chrono::milliseconds d) {
    const auto end = std::chrono::steady_clock::now() + d;
    while (std::chrono::steady_clock::now() < end) test.SpinOnce(std::chrono::milliseconds(5));
  };

  // Probe with the first view until the sink has received one (ZeroMQ slow joiner). Probes
  // lost before the connection precede the sink's window and are not "lost".
  const scene::Pose a = BasePose();
  const SinkFrame probe = RenderedFrame(a, 100.0, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (views_received == 0 && std::chrono::steady_clock::now() < deadline) {
    pub->Publish(ToView(probe));
    spin_for(std::chrono::milliseconds(100));
  }
  INFO(stderr_text());
  REQUIRE(views_received > 0);

  // Eight more views along a path; the 5th one's seq is skipped (a lost message), the 3rd
  // claims a pose 10 cm off.
  uint64_t lost_seq = 0;
  for (int i = 1; i <= 8; ++i) {
    SinkFrame f = RenderedFrame(Moved(a, 0.01 * i, 0.0, 0.0, 0.3 * i), 100.0 + 0.1 * i, 0);
    if (i == 3) f.pose = Moved(f.pose, 0.1, 0.0, 0.0);
    if (i == 5) lost_seq = pub->Raw().NextSeq();
    pub->Publish(ToView(f));
    spin_for(std::chrono::milliseconds(20));
  }
  spin_for(std::chrono::milliseconds(500));
  REQUIRE(::kill(pid, SIGTERM) == 0);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  reaper.reaped = true;
  INFO(stderr_text());
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);

  std::ifstream summary_in(out_dir + "/summary.json");
  REQUIRE(summary_in.good());
  const nlohmann::json summary = nlohmann::json::parse(summary_in);
  INFO(summary.dump(2));
  REQUIRE(summary["sequences"].size() == 1);
  const nlohmann::json& seq = summary["sequences"].begin().value();
  CHECK(seq["missing"] == nlohmann::json::array({{lost_seq, lost_seq}}));
  CHECK(summary["total_missing"] == 1);
  CHECK(summary["check"]["enabled"] == true);
  CHECK(summary["check"]["flagged"].get<int>() >= 1);

  // Nothing acknowledged is missing on disk: every seq of the window except the lost one is
  // listed, and every listed file is readable.
  const auto lines = DataLines(out_dir + "/frames.txt");
  CHECK(lines.size() == summary["frames_written"].get<size_t>());
  std::set<uint64_t> listed;
  int failed = 0;
  for (const auto& line : lines) {
    const auto t = Split(line);
    REQUIRE(t.size() == 9);
    listed.insert(std::stoull(t[2]));
    failed += t[4] == "fail";
    CHECK(!cv::imread(out_dir + "/" + t[8], cv::IMREAD_UNCHANGED).empty());
  }
  CHECK(failed >= 1);
  const uint64_t first = seq["first_seq"], last = seq["last_seq"];
  for (uint64_t s = first; s <= last; ++s) {
    if (s == lost_seq) {
      CHECK(listed.count(s) == 0);
    } else {
      CHECK(listed.count(s) == 1);
    }
  }
  for (const auto& line : DataLines(out_dir + "/depth.txt")) {
    const cv::Mat d = cv::imread(out_dir + "/" + Split(line)[1], cv::IMREAD_UNCHANGED);
    CHECK(d.type() == CV_16UC1);
  }
}

}  // namespace
}  // namespace p2i::slam_sink
