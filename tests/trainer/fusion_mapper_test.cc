/// @file fusion_mapper_test.cc
/// @brief The trainer node's online mapping (method fusion): versions every N integrated frames,
/// a last one at Stop, pruning, numbering across restarts, a changed camera refused, a full
/// queue dropping (counted), every version loadable by the synthesizer's side, and the online
/// fine-tuning of the refinement (refine_tuner.h) carried by the versions.
#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <thread>

#include "fusion/fusion_version_io.h"
#include "model/metrics.h"
#include "model/refiner.h"
#include "nodes/trainer/fusion_mapper.h"
#include "tests/trainer/trainer_test_util.h"

namespace p2i::trainer {
namespace {

namespace fs = std::filesystem;

FusionMapperOptions Options(const std::string& dir) {
  FusionMapperOptions o;
  o.work_dir = dir;
  o.publish_every_frames = 5;
  o.keep_versions = 2;
  o.keep_seconds = 0.0;  // versions pruned by count alone (the age guard: fusion_version_test.cc)
  o.scene.blend.keyframe_min_distance = 0.05;
  return o;
}

/// Polls `done` every 10 ms for up to `seconds`; returns its last value.
template <typename Pred>
bool WaitUntil(Pred done, int seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (!done() && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  return done();
}

struct Published {
  std::vector<model::FusionVersionManifest> manifests;
  std::vector<std::string> dirs;
  FusionMapper::VersionCallback Callback() {
    return [this](const model::FusionVersionManifest& m, const std::string& dir) {
      manifests.push_back(m);
      dirs.push_back(dir);
    };
  }
};

}  // namespace

TEST_CASE("fusion mapper: a version every N frames and at Stop, pruned, loadable", "[unit]") {
  const std::string dir = testing::TempDir("fusion_mapper");
  const scene::RgbdDataset frames = testing::SimFrames(12);
  REQUIRE(frames.frames.size() == 12);
  Published published;
  {
    FusionMapper mapper(Options(dir), published.Callback());
    for (const auto& f : frames.frames) mapper.Submit(f, frames.camera, /*wait=*/true);
    // The same pose again is fused but is no new keyframe (keyframe_min_distance 5 cm).
    mapper.Submit(frames.frames[5], frames.camera, /*wait=*/true);
    mapper.Stop();
    const FusionMapper::Stats st = mapper.GetStats();
    CHECK(st.received == 13);
    CHECK(st.integrated == 13);
    CHECK(st.dropped == 0);
    CHECK(st.versions == 3);
    CHECK(st.keyframes == 12);
  }
  REQUIRE(published.manifests.size() == 3);
  CHECK(published.manifests[0].version == 1);
  CHECK(published.manifests[0].frames_integrated == 5);
  CHECK(published.manifests[1].frames_integrated == 10);
  CHECK(published.manifests[2].frames_integrated == 13);  // the last one, at Stop
  CHECK(published.manifests[2].keyframe_count == 12);
  CHECK(published.manifests[2].keyframe_count >= published.manifests[0].keyframe_count);
  CHECK(model::ListFusionVersions(dir + "/versions") == std::vector<uint64_t>{2, 3});

  // The synthesizer's side builds each kept version; the last reproduces a mapped frame.
  fusion::LoadedFusionVersion v = fusion::LoadFusionVersion(published.dirs[2], {});
  CHECK(v.synthesizer->Camera().image_width == 48);
  CHECK(v.synthesizer->scene().keyframes().size() == published.manifests[2].keyframe_count);
  const scene::RgbdSample view = v.synthesizer->Render(frames.frames[6].pose);
  CHECK(model::Psnr(view.rgb, frames.frames[6].rgb) > 22.0);
  CHECK(v.refine_path.empty());

  // A restart maps afresh and numbers on; the first session's keyframes go with its versions.
  Published second;
  {
    FusionMapper mapper(Options(dir), second.Callback());
    for (size_t i = 0; i < 10; ++i) mapper.Submit(frames.frames[i], frames.camera, true);
  }  // the destructor stops (and publishes nothing more: 10 is a multiple of 5)
  REQUIRE(second.manifests.size() == 2);
  CHECK(second.manifests[0].version == 4);
  CHECK(second.manifests[0].frames_integrated == 5);
  CHECK(model::ListFusionVersions(dir + "/versions") == std::vector<uint64_t>{4, 5});
  CHECK_FALSE(fs::exists(dir + "/keyframes_s000001"));
  CHECK(fs::exists(dir + "/keyframes_s000004"));
}

TEST_CASE("fusion mapper: a camera's frames are integrated while a version is being written", "[unit]") {
  const std::string dir = testing::TempDir("fusion_mapper_async");
  const scene::RgbdDataset frames = testing::SimFrames(12);
  FusionMapperOptions o = Options(dir);
  o.queue_frames = 16;  // nothing dropped: what is measured is whether they are integrated
  std::atomic<bool> release{false};
  std::atomic<int> calls{0};
  FusionMapper mapper(o, [&](const model::FusionVersionManifest&, const std::string&) {
    ++calls;
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  });
  for (size_t i = 0; i < 5; ++i) mapper.Submit(frames.frames[i], frames.camera, true);
  // Version 1's write holds the writer thread (its callback, the last step of a write, waits).
  REQUIRE(WaitUntil([&] { return calls.load() == 1; }, 60));
  for (size_t i = 5; i < 12; ++i) mapper.Submit(frames.frames[i], frames.camera);  // as a camera
  const bool integrated_meanwhile = WaitUntil([&] { return mapper.GetStats().integrated == 12; }, 30);
  const FusionMapper::Stats during = mapper.GetStats();
  release = true;
  CHECK(integrated_meanwhile);
  CHECK(during.versions == 1);
  mapper.Stop();
  const FusionMapper::Stats st = mapper.GetStats();
  CHECK(st.dropped == 0);
  // Version 2 was due at frame 10 with version 1 still being written: it was taken at the first
  // frame after that write, or at Stop with the last frames.
  CHECK(st.versions >= 2);
  CHECK(st.versions <= 3);
  CHECK(calls.load() == static_cast<int>(st.versions));
  const std::vector<uint64_t> kept = model::ListFusionVersions(dir + "/versions");
  REQUIRE_FALSE(kept.empty());
  CHECK(model::ReadFusionVersion(model::FusionVersionDir(dir + "/versions", kept.back())).frames_integrated == 12);
}

TEST_CASE("fusion mapper: a version callback that throws is counted, and the next versions still come",
          "[unit]") {
  const std::string dir = testing::TempDir("fusion_mapper_callback_throws");
  const scene::RgbdDataset frames = testing::SimFrames(12);
  std::vector<uint64_t> seen;
  FusionMapper mapper(Options(dir), [&](const model::FusionVersionManifest& m, const std::string&) {
    seen.push_back(m.version);
    if (m.version == 1) throw std::runtime_error("the transport is gone");
  });
  for (const auto& f : frames.frames) mapper.Submit(f, frames.camera, true);
  mapper.Stop();
  const FusionMapper::Stats st = mapper.GetStats();
  CHECK(seen == std::vector<uint64_t>{1, 2, 3});  // at 5, 10 and at Stop
  CHECK(st.versions == 3);
  CHECK(st.integrated == 12);
  CHECK_THAT(st.last_error, Catch::Contains("the transport is gone"));
}

TEST_CASE("fusion mapper: another camera is refused, a full queue drops the oldest", "[unit]") {
  const std::string dir = testing::TempDir("fusion_mapper_refuse");
  const scene::RgbdDataset frames = testing::SimFrames(30);
  Published published;
  FusionMapperOptions o = Options(dir);
  o.queue_frames = 1;
  o.publish_every_frames = 1000;
  FusionMapper mapper(o, published.Callback());
  mapper.Submit(frames.frames[0], frames.camera, true);
  scene::CameraInfo other = frames.camera;
  other.camera_matrix[0] *= 1.5;
  mapper.Submit(frames.frames[1], other, true);
  WaitUntil([&] { return mapper.GetStats().rejected > 0; }, 20);
  for (const auto& f : frames.frames) mapper.Submit(f, frames.camera);  // no wait: as a camera
  mapper.Stop();
  const FusionMapper::Stats st = mapper.GetStats();
  CHECK(st.rejected == 1);
  CHECK_THAT(st.last_error, Catch::Contains("camera differs"));
  CHECK(st.dropped > 0);  // 30 frames submitted at once, integration is milliseconds each
  CHECK(st.received == st.integrated + st.dropped + st.rejected);
  REQUIRE(published.manifests.size() == 1);  // at Stop
  CHECK(published.manifests[0].frames_integrated == st.integrated);

  FusionMapperOptions bad = Options(dir);
  bad.refine_net = dir + "/missing.pt";
  CHECK_THROWS_WITH(FusionMapper(bad, nullptr), Catch::Contains("refine_net: no file"));
  bad = Options(dir);
  bad.publish_every_frames = 0;
  CHECK_THROWS_WITH(FusionMapper(bad, nullptr), Catch::Contains("publish_every_frames"));
  bad = Options(dir);
  bad.keep_seconds = -1.0;
  CHECK_THROWS_WITH(FusionMapper(bad, nullptr), Catch::Contains("keep_seconds must be finite and >= 0"));
}

TEST_CASE("fusion mapper: the refinement is fine-tuned online and carried by the next version",
          "[unit]") {
  const std::string dir = testing::TempDir("fusion_mapper_refine");
  const scene::RgbdDataset frames = testing::SimFrames(12);
  Published published;
  FusionMapperOptions o = Options(dir);
  o.publish_every_frames = 4;
  o.refine_finetune_steps = 3;
  o.refine_window_keyframes = 8;
  FusionMapper mapper(o, published.Callback());
  // Version 1 (4 keyframes: fewer than min_keyframes 8, the offer is skipped), version 2 (8).
  for (size_t i = 0; i < 8; ++i) mapper.Submit(frames.frames[i], frames.camera, true);
  REQUIRE(WaitUntil([&] { return mapper.GetStats().refine_rounds > 0; }, 120));
  REQUIRE(mapper.GetStats().refine_rounds == 1);
  // No frame comes: the new net goes out in a version of its own (same map, 8 frames).
  REQUIRE(WaitUntil([&] { return mapper.GetStats().versions >= 3; }, 60));
  REQUIRE(mapper.GetStats().versions == 3);
  for (size_t i = 8; i < 12; ++i) mapper.Submit(frames.frames[i], frames.camera, true);
  mapper.Stop();
  const FusionMapper::Stats st = mapper.GetStats();
  CHECK(st.versions == 4);
  CHECK(st.refine_steps >= 3);  // a second round (12 keyframes) may have finished before Stop
  CHECK(std::isfinite(st.refine_loss));
  CHECK(st.refine_loss > 0.0);
  REQUIRE(published.dirs.size() == 4);
  // Versions before the first round carry no net (refine_net is ""), the ones after it do, with
  // the net's step count in the manifest.
  CHECK(published.manifests[0].refine_file.empty());
  CHECK(published.manifests[1].refine_file.empty());
  CHECK(published.manifests[2].refine_file == "refine.pt");
  CHECK(published.manifests[2].step == 3);
  CHECK(published.manifests[2].frames_integrated == 8);
  CHECK(published.manifests[3].step == 3);
  CHECK(published.manifests[3].frames_integrated == 12);
  const fusion::LoadedFusionVersion v4 = fusion::LoadFusionVersion(published.dirs[3], {});
  REQUIRE_FALSE(v4.refine_path.empty());
  CHECK(fs::path(v4.refine_path).parent_path() == fs::path(published.dirs[3]));  // a copy
  CHECK(model::Refiner::Load(v4.refine_path)->total_steps() == 3);
  CHECK(model::Refiner::Load(dir + "/refine/online_refine_000001.pt")->total_steps() == 3);

  FusionMapperOptions bad = Options(dir);
  bad.refine_finetune_steps = -1;
  CHECK_THROWS_WITH(FusionMapper(bad, nullptr), Catch::Contains("refine_finetune_steps must be >= 0"));
  bad.refine_finetune_steps = 5;
  bad.refine_view_width = 4;
  CHECK_THROWS_WITH(FusionMapper(bad, nullptr), Catch::Contains("view_width must be >= 16"));
}

TEST_CASE("refine tuner: too few keyframes are skipped, a round stops at Stop and writes nothing",
          "[unit]") {
  const std::string dir = testing::TempDir("refine_tuner");
  const scene::RgbdDataset frames = testing::SimFrames(10);
  RefineTunerOptions o;
  o.out_dir = dir + "/nets";
  o.min_keyframes = 4;
  o.steps_per_round = 2;
  {
    RefineTuner tuner(o);
    tuner.Offer({frames.frames.begin(), frames.frames.begin() + 3}, frames.camera);
    REQUIRE(WaitUntil([&] { return tuner.GetStats().offers_skipped > 0; }, 60));
    CHECK(tuner.GetStats().offers_skipped == 1);
    CHECK_THAT(tuner.GetStats().last_error, Catch::Contains("fewer than min_keyframes 4"));
    CHECK(tuner.LatestNet().path.empty());
    // Three rounds: the step count carries on; a round's file, and the one before it, stay.
    for (uint64_t r = 1; r <= 3; ++r) {
      tuner.Offer(frames.frames, frames.camera);
      REQUIRE(tuner.WaitForRounds(r, 120.0));
    }
    CHECK(tuner.LatestNet().path == o.out_dir + "/online_refine_000003.pt");
    CHECK(tuner.LatestNet().steps == 6);
    CHECK(tuner.GetStats().total_steps == 6);
    CHECK(tuner.GetStats().last_error.empty());
    CHECK(model::Refiner::Load(tuner.LatestNet().path)->total_steps() == 6);
    CHECK(model::Refiner::Load(o.out_dir + "/online_refine_000002.pt")->total_steps() == 4);
    CHECK_FALSE(fs::exists(o.out_dir + "/online_refine_000001.pt"));
  }
  // A round far too long to finish: Stop ends it between two steps, and no file is written.
  o.out_dir = dir + "/long";
  o.steps_per_round = 1000000;
  RefineTuner tuner(o);
  tuner.Offer(frames.frames, frames.camera);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  tuner.Stop();
  CHECK(tuner.GetStats().rounds == 0);
  CHECK(fs::is_empty(o.out_dir));

  RefineTunerOptions bad = o;
  bad.net = dir + "/missing.pt";
  CHECK_THROWS_WITH(RefineTuner(bad), Catch::Contains("net: no file"));
  bad = o;
  bad.steps_per_round = 0;
  CHECK_THROWS_WITH(RefineTuner(bad), Catch::Contains("steps_per_round must be >= 1"));
}

}  // namespace p2i::trainer
