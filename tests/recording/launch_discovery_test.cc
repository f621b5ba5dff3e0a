/// @file launch_discovery_test.cc
/// @brief `p2i record -a`, p2i_foxglove_bridge and python/p2i_client.py find a running
/// `p2i launch` without P2I_RUN_DIR exported, as `p2i topic list` does (one rule:
/// runtime::DiscoveryRunDirs, nodes/runtime/graph_discovery.h).
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "nodes/runtime/graph_discovery.h"
#include "tests/foxglove_bridge/raw_ws_client.h"
#include "tests/process_util.h"
#include "tests/recording/recording_test_util.h"
#include "tests/test_paths.h"

namespace {

const char* kTopic = "/record_discovery_probe/pose";

/// Unsets P2I_RUN_DIR in this process (and so in its children) for its lifetime.
class NoRunDirExport {
 public:
  NoRunDirExport() {
    if (const char* v = std::getenv("P2I_RUN_DIR")) {
      had_ = true;
      old_ = v;
    }
    unsetenv("P2I_RUN_DIR");
  }
  ~NoRunDirExport() {
    if (had_) setenv("P2I_RUN_DIR", old_.c_str(), 1);
  }

 private:
  bool had_ = false;
  std::string old_;
};

}  // namespace

// long-function: one scenario: one launch without exports found in turn by record -a,
// the Foxglove bridge and the Python client (one launch start-up shared by the three).
TEST_CASE("record -a, the Foxglove bridge and the Python client find a launch without exports",
          "[integration]") {
  using namespace p2i::testing;
  NoRunDirExport no_export;
  const std::string tmp = p2i::recording::testing::TempDir("launch_discovery");
  const std::string bin = BinDir(), p2i = "env -u P2I_RUN_DIR " + bin + "/p2i";
  const pid_t launch = StartLaunch(
      bin, {SourceDir() + "/tests/recording/discovery_probe.yaml"}, "", tmp + "/launch.log");
  const std::string list = RunCommandUntil(p2i + " topic list 2>&1", kTopic);
  INFO(list);
  REQUIRE(list.find(kTopic) != std::string::npos);
  // The shared rule itself: a launch-* run dir is among the dirs discovery reads.
  bool launch_dir = false;
  for (const auto& d : p2i::runtime::DiscoveryRunDirs())
    launch_dir = launch_dir || d.find("/launch-") != std::string::npos;
  CHECK(launch_dir);

  {  // p2i record -a records the launch's topics
    int code = 0;
    const std::string file = tmp + "/all.mcap";
    const std::string rec =
        RunCommand(p2i + " record -a -o " + file + " --duration 2 2>&1", &code);
    INFO(rec);
    CHECK(code == 0);
    const std::string info = RunCommand(p2i + " info " + file + " --json 2>&1", &code);
    INFO(info);
    REQUIRE(code == 0);
    const auto j = nlohmann::json::parse(info, nullptr, false);
    REQUIRE(!j.is_discarded());
    uint64_t count = 0;
    for (const auto& t : j["topics"])
      if (t["topic"] == kTopic) count = t["count"].get<uint64_t>();
    CHECK(count > 5);  // 20 Hz for 2 s, minus connection time
  }

  {  // p2i_foxglove_bridge advertises and streams the launch's topics
    const std::string port_file = tmp + "/bridge.port";
    Process bridge({bin + "/p2i_foxglove_bridge", "port:=0", "port_file:=" + port_file,
                    "foxglove:=false", "discovery_period:=0.2", "status_period:=0"});
    int port = 0;
    for (int i = 0; i < 200 && port == 0; ++i) {
      std::ifstream(port_file) >> port;
      if (port == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    REQUIRE(port > 0);
    RawWs ws(port);
    REQUIRE(ws.ok());
    REQUIRE(ws.Handshake("foxglove.websocket.v1").find(" 101 ") != std::string::npos);
    uint32_t channel = 0;
    ws.WaitText([&](const nlohmann::json& j) {
      if (j["op"] != "advertise") return false;
      for (const auto& ch : j["channels"])
        if (ch["topic"] == kTopic) channel = ch["id"];
      return channel != 0;
    });
    REQUIRE(channel != 0);
    ws.SendFrame(1, nlohmann::json{{"op", "subscribe"},
                                   {"subscriptions", {{{"id", 7}, {"channelId", channel}}}}}
                        .dump());
    bool got = false;
    uint8_t op = 0;
    std::string payload;
    for (int i = 0; i < 100 && !got; ++i)
      got = ws.ReadFrame(&op, &payload, 200) && op == 2 && payload.size() > 13 &&
            payload[0] == 0x01 && payload[1] == 7;
    CHECK(got);
  }

  {  // python/p2i_client.py subscribes to a launch's topic
    int code = 0;
    RunCommand("/usr/bin/python3 -c 'import zmq, google.protobuf' 2>/dev/null", &code);
    if (code != 0) {
      WARN("python3-zmq / python3-protobuf missing: Python part not run");
    } else {
      const std::string out = RunCommand(
          "env -u P2I_RUN_DIR P2I_PYTHON_DIR=" + bin + "/../python /usr/bin/python3 " +
              SourceDir() + "/python/p2i_client.py subscribe " + kTopic +
              " --count 2 --timeout 10 2>&1",
          &code);
      INFO(out);
      CHECK(code == 0);
      CHECK(out.find("seq") != std::string::npos);
    }
  }
  CHECK(StopLaunch(launch) == 0);
  std::filesystem::remove_all(tmp);
}
