/// @file graph_tools_discovery_test.cc
/// @brief `p2i node list`, `p2i param list/get/set` and `p2i service list/call` find the nodes
/// of a running `p2i launch` from another shell with no P2I_RUN_DIR exported, as `p2i topic`
/// does (runtime::DiscoverGraph): the launch makes /tmp/p2i-$UID/launch-<pid>, which the old
/// tools (reading $P2I_RUN_DIR or /tmp/p2i-$UID only) never looked in.
#include <unistd.h>

#include <string>

#include <catch2/catch.hpp>

#include "tests/process_util.h"
#include "tests/test_paths.h"

namespace {

std::string Run(const std::string& command, int* code) {
  return p2i::testing::RunCommand(command + " 2>&1", code);
}

// Stops the launch also when a REQUIRE ends the test early (no orphaned nodes).
struct LaunchGuard {
  pid_t pid;
  int Stop() {
    const int code = pid > 0 ? p2i::testing::StopLaunch(pid) : -1;
    pid = -1;
    return code;
  }
  ~LaunchGuard() { Stop(); }
};

}  // namespace

TEST_CASE("p2i node / param / service reach a running launch without P2I_RUN_DIR exported",
          "[integration]") {
  const std::string ns = "discovery_tools_" + std::to_string(getpid());
  const std::string node = "/" + ns + "/synthesizer";
  const std::string log = "/tmp/p2i-discovery-tools-test-" + std::to_string(getpid()) + ".log";
  LaunchGuard launch{p2i::testing::StartLaunch(
      p2i::testing::BinDir(),
      {p2i::testing::SourceDir() + "/tests/tools/service_graph.yaml", "ns:=" + ns}, "", log)};
  // Another shell: nothing exported (P2I_PEERS too, so only the local launches count).
  const std::string p2i = "env -u P2I_RUN_DIR -u P2I_PEERS " + p2i::testing::BinDir() + "/p2i";
  int code = -1;

  // The synthesizer serves once its method is loaded (a rendered built-in dataset).
  const std::string services =
      p2i::testing::RunCommandUntil(p2i + " service list -t 2>&1", "/" + ns + "/render", 90);
  INFO(services);
  REQUIRE_THAT(services, Catch::Contains("/" + ns + "/render [RenderRequest]"));
  const std::string nodes = Run(p2i + " node list", &code);
  INFO(nodes);
  CHECK(code == 0);
  CHECK(nodes.find(node + "\n") != std::string::npos);
  const std::string verbose = Run(p2i + " node list -v", &code);
  INFO(verbose);
  CHECK(code == 0);
  CHECK_THAT(verbose, Catch::Contains("serves") &&
                         Catch::Contains("/" + ns + "/render [RenderRequest]"));

  // param: list, get, set (log_level is dynamic on every node), and the set is what get returns.
  const std::string params =
      p2i::testing::RunCommandUntil(p2i + " param list " + node + " 2>&1", "dataset_stride", 20);
  INFO(params);
  CHECK(params.find("  method\n") != std::string::npos);
  CHECK(Run(p2i + " param get " + node + " dataset_stride", &code) == "4\n");
  CHECK(code == 0);
  CHECK(Run(p2i + " param get " + node + " log_level", &code) == "info\n");
  CHECK_THAT(Run(p2i + " param set " + node + " log_level warn", &code),
             Catch::Contains("successful"));
  CHECK(code == 0);
  CHECK(Run(p2i + " param get " + node + " log_level", &code) == "warn\n");
  CHECK_THAT(Run(p2i + " param get /" + ns + "/nobody rate", &code),
             Catch::Contains("no running node") && Catch::Contains("/tmp/p2i-"));
  CHECK(code == 2);

  // service call: one render that the synthesizer answers.
  const std::string reply =
      Run(p2i + " service call /" + ns + "/render RenderRequest "
          "'{poses: [{position: {z: 1}, orientation: {w: 1}}]}' --timeout 20", &code);
  INFO(reply);
  CHECK(code == 0);
  CHECK_THAT(reply, Catch::Contains("response:") && Catch::Contains("ok: true") &&
                        Catch::Contains("nearest") &&
                        !Catch::Contains("no server"));

  CHECK(launch.Stop() == 0);
  std::remove(log.c_str());
}
