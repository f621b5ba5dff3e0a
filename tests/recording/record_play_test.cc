/// @file record_play_test.cc
/// @brief `p2i record / info / play` as processes against a real sim camera: a SIGKILLed
/// recorder leaves a readable file; a recording replayed into p2i_trainer trains it.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

#include "msgs/codec.h"
#include "nodes/runtime/node.h"
#include "nodes/runtime/shutdown.h"
#include "recording/inline_blobs.h"
#include "recording/mcap_reader.h"
#include "tests/process_util.h"
#include "tests/recording/recording_test_util.h"
#include "tests/runtime/test_util.h"
#include "tests/test_paths.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;
namespace rt = p2i::recording::testing;

namespace {

/// The sim camera along its built-in arm sweep, publishing /rgbd (with pose and camera info).
std::vector<std::string> CameraArgs(int w, int h, double rate) {
  return {testing::BinDir() + "/p2i_camera", "backend:=sim", "pose_mode:=trajectory",
          "width:=" + std::to_string(w), "height:=" + std::to_string(h),
          "rate:=" + std::to_string(rate), "status_period:=0.5"};
}

/// Messages of `path` by topic, each RgbdFrame converted back and decoded (REQUIREd to work).
std::map<std::string, int> CountDecoded(const std::string& path, recording::McapSummary* summary) {
  recording::McapReader r;
  std::string error;
  REQUIRE(r.Open(path, &error));
  std::map<std::string, int> n;
  REQUIRE(r.ReadMessages(
      [&](const recording::mcap::Channel& ch, const recording::mcap::Message& m) {
        const auto& schema = r.Summary().schemas.at(ch.schema_id);
        if (schema.name == "p2i.msgs.pb.RgbdFrame") {
          msgs::WireMessage w;
          std::string why;
          REQUIRE(recording::ExtractBlobs(schema.name, m.data, m.size, &w, &why));
          msgs::RgbdFrame f;
          REQUIRE(msgs::Decode(w, &f, &why));
          CHECK(f.rgb.width == 48);
          CHECK(f.meta.has_pose());
        }
        ++n[ch.topic];
        return true;
      },
      &error));
  *summary = r.Summary();
  return n;
}

}  // namespace

TEST_CASE("p2i record killed with SIGKILL leaves a file readable up to its last chunk",
          "[integration]") {
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir = rt::TempDir("kill");
  const std::string file = dir + "/killed.mcap";
  testing::Process camera(CameraArgs(48, 36, 20));
  REQUIRE(camera.pid() > 0);
  testing::Process rec({testing::BinDir() + "/p2i", "record", "-a", "-o", file, "--chunk-size",
                        "0.05", "--chunk-age", "0.2", "--foxglove"});
  REQUIRE(rec.pid() > 0);
  // Wait (a hang guard, not a timing assertion) until complete chunks hold 20 frames.
  recording::McapSummary s;
  const bool enough = runtime::testing::WaitUntil(
      [&] {
        recording::McapReader r;
        std::string error;
        if (!std::filesystem::exists(file) || !r.Open(file, &error)) return false;
        for (const auto& [id, ch] : r.Summary().channels) {
          const auto c = r.Summary().stats.channel_message_counts.find(id);
          if (ch.topic == "/rgbd" && c != r.Summary().stats.channel_message_counts.end() &&
              c->second >= 20)
            return true;
        }
        return false;
      },
      std::chrono::seconds(30));
  REQUIRE(enough);
  kill(rec.pid(), SIGKILL);
  CHECK(rec.Wait() == -SIGKILL);
  const auto counts = CountDecoded(file, &s);
  CHECK_FALSE(s.has_summary);
  CHECK_FALSE(s.has_footer);
  CHECK(counts.at("/rgbd") >= 20);
  // The Foxglove channels recorded beside it.
  CHECK(counts.count("/rgbd/foxglove/rgb"));
  CHECK(counts.count("/rgbd/foxglove/tf"));
  int code = -1;
  const std::string info = testing::RunCommand(testing::BinDir() + "/p2i info " + file + " 2>&1", &code);
  INFO(info);
  CHECK(code == 0);
  CHECK(info.find("Summary:           none") != std::string::npos);
  CHECK(std::regex_search(info, std::regex("Topic: /rgbd \\| Type: p2i.msgs.pb.RgbdFrame \\| Count: [0-9]+")));
  CHECK(info.find("foxglove.RawImage") != std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("p2i record -> info -> play into p2i_trainer trains from the recording",
          "[integration]") {
  runtime::Shutdown::ResetForTesting();
  runtime::testing::ScopedRunDir run_dir;
  const std::string dir = rt::TempDir("train");
  const std::string file = dir + "/capture.mcap";
  {
    testing::Process camera(CameraArgs(48, 36, 20));
    int code = -1;
    const std::string out = testing::RunCommand(
        testing::BinDir() + "/p2i record /rgbd -o " + file + " --duration 2.5 2>&1", &code);
    INFO(out);
    REQUIRE(code == 0);
  }
  int code = -1;
  const std::string info = testing::RunCommand(testing::BinDir() + "/p2i info " + file + " 2>&1", &code);
  INFO(info);
  REQUIRE(code == 0);
  CHECK(info.find("Summary:           yes") != std::string::npos);
  std::smatch m;
  REQUIRE(std::regex_search(info, m, std::regex("Topic: /rgbd \\| Type: p2i.msgs.pb.RgbdFrame \\| Count: ([0-9]+) \\| Rate: ([0-9.]+) Hz")));
  const int recorded = std::stoi(m[1]);
  CHECK(recorded >= 10);
  CHECK(std::stod(m[2]) > 0);

  // --topics with no such topic is an error; --start skips the beginning.
  testing::RunCommand(testing::BinDir() + "/p2i play " + file + " --topics /nothing 2>&1", &code);
  CHECK(code == 1);
  const std::string late = testing::RunCommand(
      testing::BinDir() + "/p2i play " + file + " --start 1.5 --rate 4 --delay 0 2>&1", &code);
  INFO(late);
  CHECK(code == 0);
  REQUIRE(std::regex_search(late, m, std::regex("published ([0-9]+) messages")));
  CHECK(std::stoi(m[1]) < recorded);
  CHECK(std::stoi(m[1]) > 0);

  // The trainer learns from the replay.
  {
    std::ofstream(dir + "/tiny.yaml") << trainer::testing::TinyConfig().ToYamlString();
  }
  runtime::Node listener("listener", runtime::NodeArgs::Parse(std::vector<std::string>{}));
  std::vector<msgs::pb::ModelVersion> versions;
  uint64_t buffered = 0;
  listener.Subscribe<msgs::pb::ModelVersion>(
      "/model_version", [&](const msgs::pb::ModelVersion& v) { versions.push_back(v); });
  listener.Subscribe<msgs::pb::TrainerStatus>(
      "/trainer_status", [&](const msgs::pb::TrainerStatus& s) { buffered = s.buffer_size(); });
  listener.Start();
  testing::Process trainer({testing::BinDir() + "/p2i_trainer", "config:=" + dir + "/tiny.yaml",
                            "work_dir:=" + dir + "/work", "publish_every_steps:=4",
                            "min_frames:=4", "max_val_frames:=2", "trainer_status_period:=0.2",
                            "latch_period:=0.2"});
  REQUIRE(trainer.pid() > 0);
  testing::Process play({testing::BinDir() + "/p2i", "play", file, "--delay", "1.5"});
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (std::chrono::steady_clock::now() < deadline && versions.empty())
    listener.SpinOnce(std::chrono::milliseconds(20));
  REQUIRE_FALSE(versions.empty());
  CHECK(versions.back().version() >= 1);
  CHECK(versions.back().step() >= 1);
  CHECK(buffered >= 4);
  CHECK(play.Wait() == 0);
  CHECK(trainer.Terminate() == 0);
  std::filesystem::remove_all(dir);
}
