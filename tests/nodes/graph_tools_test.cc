/// @file graph_tools_test.cc
/// @brief What a ROS 2 user reaches for, on real node processes: `p2i node list`, `p2i topic
/// info`, `p2i topic pub`, `p2i service list/call`, `p2i topic echo` of images (a summary,
/// --save-image DIR), `--timeout` counted from the last message, `p2i topic list` without a
/// graph, node --help / --version / bad tokens, ROS 2 parameter files.
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <opencv2/imgcodecs.hpp>

#include "msgs/codec.h"
#include "nodes/runtime/raw_subscriber.h"
#include "tests/process_util.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"

namespace fs = std::filesystem;
using p2i::runtime::testing::ScopedRunDir;
using p2i::runtime::testing::WaitUntil;
using p2i::testing::Process;
using p2i::testing::RunCommand;

namespace {

std::string Bin(const std::string& name) { return p2i::testing::BinDir() + "/" + name; }

std::string Run(const std::string& cmd, int* code) { return RunCommand(cmd + " 2>&1", code); }

}  // namespace

TEST_CASE("p2i node list, topic info, topic pub and service call on running nodes",
          "[integration]") {
  ScopedRunDir run_dir;
  Process node({Bin("runtime_test_node"), "--name", "talker", "rate:=20"});
  REQUIRE(node.pid() > 0);
  int code = -1;
  REQUIRE(WaitUntil([&] { return Run(Bin("p2i") + " node list", &code).find("/talker") != std::string::npos; },
                    std::chrono::seconds(20)));
  const std::string info = Run(Bin("p2i") + " topic info /chatter", &code);
  INFO(info);
  CHECK(code == 0);
  CHECK_THAT(info, Catch::Contains("Type: PoseStamped") && Catch::Contains("Publisher count: 1") &&
                       Catch::Contains("/talker"));
  CHECK(Run(Bin("p2i") + " topic info /nothing", &code).find("no publisher") != std::string::npos);
  CHECK(code == 1);

  // topic pub: a subscriber here receives what the tool publishes, with the given fields.
  p2i::runtime::RawSubscriber sub("/typed_in", {});
  int got = 0;
  double z = 0;
  std::thread reader([&] {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (got < 2 && std::chrono::steady_clock::now() < end) {
      p2i::msgs::WireMessage w;
      p2i::msgs::pb::Header h;
      if (!sub.Receive(&w, &h, std::chrono::milliseconds(100))) continue;
      p2i::msgs::pb::PoseStamped p;
      std::string err;
      if (p2i::msgs::Decode(w, &p, &err)) {
        ++got;
        z = p.pose().position().z();
      }
    }
  });
  const std::string pub = Run(Bin("p2i") + " topic pub /typed_in PoseStamped "
                              "'{pose: {position: {z: 1.5}, orientation: {w: 1}}}' -r 10 -t 6", &code);
  reader.join();
  INFO(pub);
  CHECK(code == 0);
  CHECK(got >= 2);
  CHECK(z == 1.5);
  CHECK(Run(Bin("p2i") + " topic pub /x NoSuchType '{}' -1", &code).find("unknown message type") !=
        std::string::npos);
  CHECK(code == 2);

  // service list / call.
  CHECK(Run(Bin("p2i") + " service list -t", &code).find("/echo [PoseRequest]") != std::string::npos);
  const std::string reply = Run(Bin("p2i") + " service call /echo PoseRequest "
                                "'{pose: {position: {x: 2.25}, orientation: {w: 1}}}'", &code);
  INFO(reply);
  CHECK(code == 0);
  CHECK_THAT(reply, Catch::Contains("type: PoseStamped") && Catch::Contains("x: 2.25"));
}

TEST_CASE("p2i topic echo: images as a summary, --save-image, --timeout from the last message",
          "[integration]") {
  ScopedRunDir run_dir;
  const fs::path dir = fs::path(run_dir.Path()) / "images";
  Process camera({Bin("p2i_camera"), "width:=64", "height:=48", "rate:=4", "pose_mode:=trajectory",
                  "status_period:=0"});
  REQUIRE(camera.pid() > 0);
  int code = -1;
  // 4 frames/s for 6 frames with --timeout 1: gaps of 0.25 s never reach it (the old
  // "from the start" timeout failed after 1 s).
  const std::string out = Run(Bin("p2i") + " topic echo /rgbd -n 6 --timeout 1 --save-image " +
                              dir.string(), &code);
  INFO(out.substr(0, 2000));
  CHECK(code == 0);
  CHECK_THAT(out, Catch::Contains("<blob 0: 64 x 48 RGB8, 9216 bytes>"));
  CHECK(out.size() < 20000);  // a summary, not the pixels
  const cv::Mat rgb = cv::imread((dir / "000000_rgb.png").string(), cv::IMREAD_UNCHANGED);
  CHECK(rgb.cols == 64);
  CHECK(rgb.rows == 48);
  const cv::Mat depth = cv::imread((dir / "000005_depth.png").string(), cv::IMREAD_UNCHANGED);
  CHECK(depth.type() == CV_16UC1);
  // A topic nobody publishes: the timeout fires (exit 1).
  CHECK(Run(Bin("p2i") + " topic echo /silent --timeout 0.5", &code).find("no message") !=
        std::string::npos);
  CHECK(code == 1);
}

TEST_CASE("p2i topic list without a running graph says so", "[integration]") {
  ScopedRunDir run_dir;
  int code = -1;
  const std::string out = Run(Bin("p2i") + " topic list", &code);
  CHECK(code == 0);
  CHECK_THAT(out, Catch::Contains("no running graph") && Catch::Contains(run_dir.Path()));
  CHECK_THAT(Run(Bin("p2i") + " node list", &code), Catch::Contains("no running nodes"));
}

TEST_CASE("nodes: --help, --version, bad tokens, ROS 2 parameter files, exit codes",
          "[integration]") {
  ScopedRunDir run_dir;
  int code = -1;
  for (const char* exe : {"p2i_camera", "p2i_pose_source", "p2i_slam_sink", "p2i_synthesizer",
                          "p2i_trainer", "p2i_monitor", "p2i_pool", "p2i_foxglove_bridge"}) {
    INFO(exe);
    const std::string help = Run(Bin(exe) + " --help", &code);
    CHECK(code == 0);
    CHECK_THAT(help, Catch::Contains("usage: ") && Catch::Contains("log_level (string, default info)") &&
                         Catch::Contains("Exit codes: 0 clean shutdown, 1 runtime error, 2 usage"));
    CHECK(Run(Bin(exe) + " --version", &code).find(std::string(exe) + " ") == 0);
    CHECK(code == 0);
    CHECK_THAT(Run(Bin(exe) + " rate=10", &code), Catch::Contains("did you mean rate:=10"));
    CHECK(code == 2);
  }
  CHECK_THAT(Run(Bin("p2i_pose_source") + " --help", &code),
             Catch::Contains("rate (double, default 20)"));
  // --help binds nothing (the pool's frontend, the bridge's port are not opened).
  CHECK_THAT(Run(Bin("p2i_pool") + " --help", &code), Catch::Contains("max_queue (int"));
  CHECK_THAT(Run(Bin("p2i_foxglove_bridge") + " --help port_file:=" + run_dir.Path() + "/port", &code),
             Catch::Contains("port (int, default 8765)"));
  CHECK_FALSE(fs::exists(run_dir.Path() + "/port"));
  CHECK((!fs::exists(run_dir.Path() + "/registry") || fs::is_empty(run_dir.Path() + "/registry")));
  // The pool's `endpoints` entry for its service is its frontend; other keys are errors.
  CHECK_THAT(Run(Bin("p2i_pool") + " 'endpoints:={rendr: \"ipc:///tmp/x\"}'", &code),
             Catch::Contains("'rendr'") && Catch::Contains("/render"));
  CHECK(code == 2);
  {
    const std::string frontend = "ipc://" + run_dir.Path() + "/my_pool.ipc";
    Process pool({Bin("p2i_pool"), "endpoints:={render: \"" + frontend + "\"}"});
    REQUIRE(pool.pid() > 0);
    CHECK(WaitUntil([&] {
      return Run(Bin("p2i") + " service list -t 2>&1", &code).find("/render") != std::string::npos &&
             Run(Bin("p2i") + " topic list -v 2>&1", &code).find(frontend) != std::string::npos;
    }, std::chrono::seconds(20)));
  }
  // slam_sink validates before it creates anything.
  const fs::path out = fs::path(run_dir.Path()) / "sink";
  CHECK_THAT(Run(Bin("p2i_slam_sink") + " out_dir:=" + out.string() + " zz:=1", &code),
             Catch::Contains("unknown parameter 'zz'"));
  CHECK(code == 2);
  CHECK_FALSE(fs::exists(out));
  CHECK_THAT(Run(Bin("p2i_slam_sink") + " --help out_dir:=" + out.string(), &code),
             Catch::Contains("out_dir (string"));
  CHECK_FALSE(fs::exists(out));
  // endpoints keys must name a topic or service.
  CHECK_THAT(Run(Bin("p2i_pose_source") + " 'endpoints:={poes: \"ipc:///tmp/x\"}'", &code),
             Catch::Contains("'poes'") && Catch::Contains("/pose"));
  CHECK(code == 2);
  // ROS 2 parameter file: /** for everyone, the node's own section, other nodes ignored.
  const std::string params = run_dir.Path() + "/ros.yaml";
  std::ofstream(params) << "/**:\n  ros__parameters:\n    rate: 5.0\n    zz_wrong_for_all: 1\n"
                           "pose_source:\n  ros__parameters:\n    zz_wrong_for_all: 2\n";
  CHECK_THAT(Run(Bin("p2i_pose_source") + " --params-file " + params, &code),
             Catch::Contains("unknown parameter 'zz_wrong_for_all' (from " + params));
  CHECK(code == 2);
  std::ofstream(params) << "/**:\n  ros__parameters:\n    rate: fast\n"
                           "other_node:\n  ros__parameters:\n    zz_other: 1\n"
                           "/pose_source:\n  ros__parameters:\n    zz_mine: 1\n";
  const std::string ran = Run(Bin("p2i_pose_source") + " --params-file " + params, &code);
  INFO(ran);
  CHECK(code == 2);
  CHECK_THAT(ran, Catch::Contains("parameter 'rate' from " + params));  // /** applies
  std::ofstream(params) << "other_node:\n  ros__parameters:\n    zz_other: 1\n"
                           "/pose_source:\n  ros__parameters:\n    zz_mine: 1\n";
  const std::string mine = Run(Bin("p2i_pose_source") + " --params-file " + params, &code);
  CHECK_THAT(mine, Catch::Contains("'zz_mine'") && !Catch::Contains("zz_other"));
}

TEST_CASE("p2i param list/get/set on a running node (set where declared dynamic)",
          "[integration]") {
  ScopedRunDir run_dir;
  Process node({Bin("runtime_test_node"), "--name", "talker", "rate:=20"});
  REQUIRE(node.pid() > 0);
  int code = -1;
  REQUIRE(WaitUntil([&] { return Run(Bin("p2i") + " param list /talker", &code).find("rate") != std::string::npos; },
                    std::chrono::seconds(20)));
  CHECK_THAT(Run(Bin("p2i") + " param list /talker -d", &code),
             Catch::Contains("log_level (string, default info, dynamic)") &&
                 Catch::Contains("rate (double, default 50)"));
  CHECK(Run(Bin("p2i") + " param get /talker rate", &code) == "20\n");
  CHECK(Run(Bin("p2i") + " param get /talker log_level", &code) == "info\n");
  CHECK_THAT(Run(Bin("p2i") + " param set /talker log_level debug", &code),
             Catch::Contains("successful"));
  CHECK(code == 0);
  CHECK(Run(Bin("p2i") + " param get /talker log_level", &code) == "debug\n");
  CHECK_THAT(Run(Bin("p2i") + " param set /talker log_level loud", &code),
             Catch::Contains("not one of trace"));
  CHECK(code == 1);
  CHECK_THAT(Run(Bin("p2i") + " param set /talker rate 5", &code), Catch::Contains("not dynamic"));
  CHECK(code == 1);
  CHECK_THAT(Run(Bin("p2i") + " param get /nobody rate", &code), Catch::Contains("no running node"));
  CHECK(code == 2);
}

TEST_CASE("values accepted before are refused with exit 2", "[integration]") {
  ScopedRunDir run_dir;
  int code = -1;
  CHECK_THAT(Run(Bin("p2i") + " render builtin:small_office --width 0 --out " + run_dir.Path() + "/r", &code),
             Catch::Contains("--width"));
  CHECK(code == 2);
  CHECK_FALSE(fs::exists(run_dir.Path() + "/r"));
  CHECK_THAT(Run(Bin("p2i") + " train " + p2i::testing::SourceDir() +
                 "/model/presets/demo_64.yaml --data procedural --out " + run_dir.Path() +
                 "/t --steps -3", &code),
             Catch::Contains("--steps"));
  CHECK(code == 2);
  CHECK_THAT(Run(Bin("p2i_camera") + " width:=17000 height:=480", &code),
             Catch::Contains("width must be in [0, 8192] (got 17000)"));
  CHECK(code == 2);
  CHECK_THAT(Run(Bin("p2i_synthesizer") + " method:=nearest threads:=-2", &code),
             Catch::Contains("threads must be >= 1 (got -2)"));
  CHECK(code == 2);
  CHECK_THAT(Run(Bin("p2i_trainer") + " threads:=-2", &code),
             Catch::Contains("threads must be >= 1 (got -2)"));
  CHECK(code == 2);
  CHECK(Run(Bin("p2i") + " nosuchcommand", &code).find("unknown command") != std::string::npos);
  CHECK(code == 2);
}
