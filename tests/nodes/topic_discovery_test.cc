/// @file topic_discovery_test.cc
/// @brief `p2i topic` finds a running launch without P2I_RUN_DIR exported, and a graph split
/// over two launchers ("machines" a and b on loopback) works through their registry servers:
/// b's camera renders at a's poses, and `p2i topic list/hz --peer` see the other machine.
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

/// `p2i launch ARGS...` as a child with stdout+stderr in `log`; P2I_RUN_DIR as given ("" =
/// unset, the launcher then makes /tmp/p2i-$UID/launch-<pid>).
pid_t StartLaunch(const std::vector<std::string>& args, const std::string& run_dir,
                  const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (run_dir.empty()) unsetenv("P2I_RUN_DIR"); else setenv("P2I_RUN_DIR", run_dir.c_str(), 1);
    unsetenv("P2I_CURVE_DIR");
    unsetenv("P2I_PEERS");
    freopen(log.c_str(), "w", stdout);
    dup2(fileno(stdout), 2);
    const std::string exe = p2i::testing::BinDir() + "/p2i";
    std::vector<char*> argv = {const_cast<char*>(exe.c_str()), const_cast<char*>("launch")};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

int Stop(pid_t pid) {
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string Until(const std::string& command, const std::string& needle, int seconds = 20) {
  std::string out;
  int code = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    out = p2i::testing::RunCommand(command, &code);
    if (out.find(needle) != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return out;
}

}  // namespace

TEST_CASE("p2i topic list finds a running launch without P2I_RUN_DIR exported", "[integration]") {
  const std::string dir = p2i::testing::SourceDir() + "/tests/nodes";
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
  const std::string dir = p2i::testing::SourceDir() + "/tests/nodes";
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
  const std::string list = Until(p2i + " topic list -v" + peers + " 2>&1", "/rgbd");
  INFO(list);
  CHECK(list.find("/pose ") != std::string::npos);
  CHECK(list.find("via tcp://127.0.0.1:" + pa) != std::string::npos);
  CHECK(list.find("via tcp://127.0.0.1:" + pb) != std::string::npos);
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
