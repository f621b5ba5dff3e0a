/// @file topic_tool_test.cc
/// @brief `p2i topic list | echo | hz` against a real pose_source process.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <regex>
#include <string>
#include <thread>

#include <catch2/catch.hpp>

#include "tests/runtime/test_util.h"
#include "tests/process_util.h"
#include "tests/test_paths.h"

TEST_CASE("p2i topic list, echo and hz on a running pose_source", "[integration]") {
  p2i::runtime::testing::ScopedRunDir run_dir;  // sets P2I_RUN_DIR for us and the children
  const std::string bin = p2i::testing::BinDir();
  const pid_t pid = fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    const std::string exe = bin + "/p2i_pose_source";
    execl(exe.c_str(), exe.c_str(), "trajectory:=orbit", "rate:=20.0", "status_period:=0.5",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  const std::string p2i = bin + "/p2i";
  int code = -1;
  // list: the node's topics appear once it has bound them.
  std::string list;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    list = p2i::testing::RunCommand(p2i + " topic list -t 2>&1", &code);
    if (list.find("/pose") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  INFO(list);
  CHECK(code == 0);
  CHECK(std::regex_search(list, std::regex("/pose\\b.*POSE|/pose \\[")));
  CHECK(list.find("/pose_source/status") != std::string::npos);

  // echo --once prints one decoded PoseStamped with its header and position.
  const std::string echo = p2i::testing::RunCommand(p2i + " topic echo /pose --once 2>&1", &code);
  INFO(echo);
  CHECK(code == 0);
  CHECK(echo.find("seq") != std::string::npos);
  CHECK(echo.find("position") != std::string::npos);

  // hz measures the configured 20 Hz (loose bounds: a loaded 2-core box).
  const std::string hz = p2i::testing::RunCommand(p2i + " topic hz /pose --duration 3 2>&1", &code);
  INFO(hz);
  CHECK(code == 0);
  std::smatch m;
  REQUIRE(std::regex_search(hz, m, std::regex("average rate: ([0-9.]+)")));
  const double rate = std::stod(m[1]);
  CHECK(rate > 12.0);
  CHECK(rate < 28.0);

  // A topic nobody publishes is an error for echo, not a hang.
  p2i::testing::RunCommand(p2i + " topic echo /no_such_topic --once --timeout 1 2>&1", &code);
  CHECK(code != 0);

  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  CHECK(WIFEXITED(status));
}
