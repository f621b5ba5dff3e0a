/// @file fusion_version_io_test.cc
/// @brief A FusionScene written as a fusion version and built back: the same views as the scene
/// it came from (TSDF snapshot + keyframes read from their capture), the output size asked, and
/// refusals naming what is missing.
#include <catch2/catch.hpp>

#include <filesystem>

#include "fusion/fusion_version_io.h"
#include "model/metrics.h"
#include "scene/capture.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"
#include "tests/temp_dir.h"

namespace p2i::fusion {
namespace {

namespace fs = std::filesystem;

}  // namespace

TEST_CASE("fusion version: written from a scene, built back with the same views", "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_io");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(80, 60);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options;
  options.tsdf.voxel_size_m = 0.03;
  options.tsdf.block_resolution = 8;
  FusionScene fused(cam, options);
  scene::CaptureWriter keyframes(dir + "/keyframes", cam);
  scene::RgbdDataset frames;
  frames.camera = cam;
  for (size_t i = 0; i < sweep.size(); i += 8) {
    scene::RgbdSample s = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
    s.id = "f" + std::to_string(i);
    fused.AddFrame(s);
    keyframes.Append(s);
    frames.frames.push_back(s);
  }
  FusionVersionInfo info;
  info.version = 7;
  info.frames_integrated = frames.frames.size();
  info.keyframes_dir = dir + "/keyframes";
  info.keyframe_count = frames.frames.size() - 1;  // the last frame came after this version
  const std::string version_dir = WriteSceneVersion(dir + "/versions", fused, info);
  CHECK(fs::path(version_dir).filename() == "fusion_v000007");

  FusionOptions load_options;  // default voxel size and block resolution: the manifest's win
  LoadedFusionVersion v = LoadFusionVersion(version_dir, load_options, 48, 48);
  CHECK(v.manifest.voxel_size_m == 0.03);
  CHECK(v.manifest.block_resolution == 8);
  CHECK(v.synthesizer->scene().options().tsdf.voxel_size_m == 0.03);
  CHECK(v.synthesizer->scene().keyframes().size() == frames.frames.size() - 1);
  CHECK(v.synthesizer->Camera().image_width == 48);
  CHECK(v.synthesizer->Camera().image_height == 48);

  // Against the scene the version was written from, rendered at the same camera.
  FusionSynthesizer original(frames, FusionOptions{options, true}, v.synthesizer->Camera());
  const scene::Pose pose = frames.frames[frames.frames.size() / 2].pose;
  const scene::RgbdSample a = v.synthesizer->Render(pose);
  const scene::RgbdSample b = original.Render(pose);
  CHECK(model::Psnr(a.rgb, b.rgb) > 35.0);  // keyframe depth is stored in whole millimetres
  CHECK(model::ComputeDepthErrors(a.depth, b.depth).abs_rel < 1e-3);
  CHECK(v.synthesizer->LastGeometry().front().observed_fraction > 0.9);

  // A keyframe folder that lost frames, and a folder that is not a version.
  info.version = 8;
  info.keyframe_count = frames.frames.size() + 5;
  const std::string too_many = WriteSceneVersion(dir + "/versions", fused, info);
  CHECK_THROWS_WITH(LoadFusionVersion(too_many, load_options), Catch::Contains("lists"));
  CHECK_THROWS_WITH(LoadFusionVersion(dir + "/keyframes", load_options),
                    Catch::Contains("manifest.json"));
}

}  // namespace p2i::fusion
