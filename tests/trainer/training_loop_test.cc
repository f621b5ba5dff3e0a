/// @file training_loop_test.cc
/// @brief TrainingLoop on sim frames with a tiny model: versions come out in order, each a
/// loadable checkpoint, and the buffer persists.
#include <cmath>

#include <catch2/catch.hpp>

#include <filesystem>
#include <mutex>
#include <thread>

#include "model/p2i_synthesizer.h"
#include "nodes/trainer/training_loop.h"
#include "tests/trainer/trainer_test_util.h"

using namespace p2i;
using namespace p2i::trainer;

// long-function: one scenario on one work dir: rounds on a growing buffer, a restarted loop,
// a warm start; each step continues the versions and steps the previous one left.
TEST_CASE("TrainingLoop: rounds on a growing buffer publish loadable, increasing versions",
          "[slow]") {
  const std::string dir = trainer::testing::TempDir("loop");
  const scene::RgbdDataset sim = trainer::testing::SimFrames(40);
  REQUIRE(sim.frames.size() == 40);

  ReplayBuffer::Options bo;
  bo.dir = dir + "/buffer";
  bo.width = bo.height = 32;
  bo.max_mb = 1.0;
  std::vector<msgs::pb::ModelVersion> versions;
  std::vector<msgs::pb::TrainerStatus> statuses;
  std::mutex mutex;
  {
    ReplayBuffer buffer(bo);
    TrainingLoop::Options o;
    o.config = trainer::testing::TinyConfig();
    o.work_dir = dir + "/work";
    o.steps_per_round = 6;
    o.min_frames = 8;
    o.max_rounds = 3;
    o.max_val_frames = 4;
    TrainingLoop loop(
        o, &buffer,
        [&](const msgs::pb::ModelVersion& v) {
          std::lock_guard<std::mutex> lock(mutex);
          versions.push_back(v);
        },
        [&](const msgs::pb::TrainerStatus& s) {
          std::lock_guard<std::mutex> lock(mutex);
          statuses.push_back(s);
        });
    loop.Start();
    // Frames arrive while the loop runs (the first 8 let it start).
    for (const auto& f : sim.frames) {
      buffer.Add(f, sim.camera);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    while (!loop.Finished()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    REQUIRE(loop.Error() == "");
    CHECK(buffer.Size() == 40);
    // The last version's validation pose-dependence (the trainer node's val_pose_dependence;
    // -1 = never measured).
    CHECK(loop.LastPoseDependence() >= 0.0);
    CHECK(std::isfinite(loop.LastPoseDependence()));
  }
  REQUIRE(versions.size() == 3);
  for (size_t i = 0; i < versions.size(); ++i) {
    const auto& v = versions[i];
    CHECK(v.version() == i + 1);
    CHECK(v.step() == 6 * (i + 1));
    CHECK(v.width() == 32);
    REQUIRE(std::filesystem::exists(v.checkpoint_path()));
    auto synth = model::LoadSynthesizer(v.checkpoint_path());
    // ENET is trained online too: every version renders G + ENET ("g+enet" is refused for a
    // checkpoint without phase-2 steps).
    model::SynthesizerOptions with_enet;
    with_enet.stage = "g+enet";
    CHECK_NOTHROW(model::LoadSynthesizer(v.checkpoint_path(), with_enet));
    const auto view = synth->Render(sim.frames[5].pose);
    CHECK(view.rgb.cols == 32);
    CHECK(view.rgb.rows == 32);
  }
  // The versions are distinct files (later training does not rewrite an earlier one).
  CHECK(versions[0].checkpoint_path() != versions[2].checkpoint_path());
  bool trained_status = false;
  for (const auto& s : statuses)
    trained_status |= s.phase() == "training" || (s.step() > 0 && !s.losses().empty());
  CHECK(trained_status);
  CHECK(statuses.back().step() == 18);
  CHECK_FALSE(statuses.back().losses().empty());

  // The buffer is on disk: a new one reloads all 40 frames.
  ReplayBuffer reloaded(bo);
  CHECK(reloaded.Size() == 40);

  // A restarted loop continues the version numbers and the step count.
  {
    TrainingLoop::Options o;
    o.config = trainer::testing::TinyConfig();
    o.work_dir = dir + "/work";
    o.steps_per_round = 6;
    o.max_rounds = 1;
    o.max_val_frames = 4;
    std::vector<msgs::pb::ModelVersion> more;
    TrainingLoop loop(o, &reloaded, [&](const msgs::pb::ModelVersion& v) { more.push_back(v); },
                      nullptr);
    loop.Start();
    while (!loop.Finished()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    REQUIRE(loop.Error() == "");
    REQUIRE(more.size() == 1);
    CHECK(more[0].version() == 4);
    CHECK(more[0].step() == 24);
  }
  // Warm start: a fresh work dir starting from version 3's checkpoint continues from its step.
  {
    TrainingLoop::Options o;
    o.config = trainer::testing::TinyConfig();
    o.work_dir = dir + "/warm";
    o.warm_start = versions[2].checkpoint_path();
    o.steps_per_round = 6;
    o.max_rounds = 1;
    o.max_val_frames = 4;
    std::vector<msgs::pb::ModelVersion> warm;
    TrainingLoop loop(o, &reloaded, [&](const msgs::pb::ModelVersion& v) { warm.push_back(v); },
                      nullptr);
    loop.Start();
    while (!loop.Finished()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    REQUIRE(loop.Error() == "");
    REQUIRE(warm.size() == 1);
    CHECK(warm[0].version() == 1);
    CHECK(warm[0].step() == 24);
    CHECK(std::filesystem::exists(o.work_dir + "/checkpoint.pt"));
  }
  std::filesystem::remove_all(dir);
}
