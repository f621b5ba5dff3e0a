/// @file topic_discovery_test.cc
/// @brief `p2i topic` finds a running launch without P2I_RUN_DIR exported, and a graph split
/// over two launchers ("machines" a and b on loopback) works through their registry servers:
/// b's camera renders at a's poses, and `p2i topic list/hz --peer` and `p2i node list --peer`
/// see the other machine.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>

#include <catch2/catch.hpp>

#include "tests/process_util.h"
#include "tests/test_paths.h"

namespace {

pid_t StartLaunch(const std::vector<std::string>& args, const std::string& run_dir,
                  const std::string& log) {
  return p2i::testing::StartLaunch(p2i::testing::BinDir(), args, run_dir, log);
}

int Stop(pid_t pid) { return p2i::testing::StopLaunch(pid); }

std::string Until(const std::string& command, const std::string& needle, int seconds = 20) {
  return p2i::testing::RunCommandUntil(command, needle, seconds);
}

}  // namespace

TEST_CASE("p2i topic list finds a running launch without P2I_RUN_DIR exported", "[integration]") {
  const std::string dir = p2i::testing::SourceDir() + "/tests/tools";
  const std::string log = "/tmp/p2i-discovery-test-" + std::to_string(getpid()) + ".log";
  const pid_t launch = StartLaunch({dir + "/one_node.yaml"}, "", log);
  const std::string p2i = "env -u P2I_RUN_DIR " + p2i::testing::BinDir() + "/p2i";
  const std::string list = Until(p2i + " topic list 2>&1", "/discovery_probe/pose");
  INFO(list);
  CHECK(list.find("/discovery_probe/pose") != std::string::npos);
  int code = 0;
  const std::string echo = p2i::testing::RunCommand(
      p2i + " topic echo /discovery_probe/pose --once --timeout 10 2>&1", &code);
  INFO(echo);
  CHECK(code == 0);
  CHECK(echo.find("position") != std::string::npos);
  CHECK(Stop(launch) == 0);
  std::remove(log.c_str());
}

TEST_CASE("A graph split over two launchers finds its topics through their registries", "[integration]") {
  const std::string dir = p2i::testing::SourceDir() + "/tests/tools";
  const int base = 20000 + (getpid() % 20000);
  const std::string pa = std::to_string(base), pb = std::to_string(base + 1);
  const std::string tmp = "/tmp/p2i-two-machines-" + std::to_string(getpid());
  std::system(("mkdir -p " + tmp + "/a " + tmp + "/b " + tmp + "/empty").c_str());
  const std::vector<std::string> args = {dir + "/two_machines.yaml", "port_a:=" + pa,
                                         "port_b:=" + pb};
  auto with = [&](std::vector<std::string> v, const std::string& m) {
    v.push_back("--machine");
    v.push_back(m);
    return v;
  };
  const pid_t a = StartLaunch(with(args, "a"), tmp + "/a", tmp + "/a.log");
  const pid_t b = StartLaunch(with(args, "b"), tmp + "/b", tmp + "/b.log");
  // From an empty run dir, only the peers can tell where anything is.
  const std::string p2i = "env P2I_RUN_DIR=" + tmp + "/empty " + p2i::testing::BinDir() + "/p2i";
  const std::string peers = " --peer tcp://127.0.0.1:" + pa + " --peer tcp://127.0.0.1:" + pb;
  // Both launchers start at once and either may be up first: wait for a topic of each (waiting
  // for machine a's /rgbd alone failed once on a loaded box, machine b's /pose not yet there).
  Until(p2i + " topic list -v" + peers + " 2>&1", "/rgbd");
  const std::string list = Until(p2i + " topic list -v" + peers + " 2>&1", "/pose ");
  INFO(list);
  CHECK(list.find("/rgbd") != std::string::npos);
  CHECK(list.find("/pose ") != std::string::npos);
  CHECK(list.find("via tcp://127.0.0.1:" + pa) != std::string::npos);
  CHECK(list.find("via tcp://127.0.0.1:" + pb) != std::string::npos);
  // p2i node list asks the same peers: the pose_source of a and the camera of b.
  int nodes_code = -1;
  const std::string nodes =
      p2i::testing::RunCommand(p2i + " node list -v" + peers + " 2>&1", &nodes_code);
  INFO(nodes);
  CHECK(nodes_code == 0);
  CHECK_THAT(nodes, Catch::Contains("/pose_source (pid") && Catch::Contains("/camera (pid") &&
                        Catch::Contains("via tcp://127.0.0.1:" + pa) &&
                        Catch::Contains("via tcp://127.0.0.1:" + pb));
  // b's camera only renders when it gets poses, which come from a over tcp.
  int code = 0;
  const std::string hz =
      p2i::testing::RunCommand(p2i + " topic hz /rgbd --duration 3" + peers + " 2>&1", &code);
  INFO(hz);
  CHECK(hz.find("average rate") != std::string::npos);
  const std::string bw =
      p2i::testing::RunCommand(p2i + " topic bw /rgbd --duration 2" + peers + " 2>&1", &code);
  INFO(bw);
  CHECK(bw.find("summary:") != std::string::npos);
  CHECK(Stop(a) == 0);
  CHECK(Stop(b) == 0);
  std::system(("rm -rf " + tmp).c_str());
}
