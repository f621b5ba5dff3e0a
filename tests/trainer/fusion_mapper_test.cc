/// @file fusion_mapper_test.cc
/// @brief The trainer node's online mapping (method fusion): versions every N integrated frames,
/// a last one at Stop, pruning, numbering across restarts, a changed camera refused, a full
/// queue dropping (counted), and every version loadable by the synthesizer's side.
#include <catch2/catch.hpp>

#include <chrono>
#include <filesystem>
#include <thread>

#include "fusion/fusion_version_io.h"
#include "model/metrics.h"
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
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (mapper.GetStats().rejected == 0 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
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

}  // namespace p2i::trainer
