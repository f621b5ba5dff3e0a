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

/// The tests' fused scene: 3 cm voxels in 8^3 blocks (small and quick), other options default.
FusionSceneOptions CoarseOptions() {
  FusionSceneOptions options;
  options.tsdf.voxel_size_m = 0.03;
  options.tsdf.block_resolution = 8;
  return options;
}

}  // namespace

TEST_CASE("fusion version: written from a scene, built back with the same views", "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_io");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(80, 60);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options = CoarseOptions();
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

TEST_CASE("fusion version: local submaps are saved and built back", "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_io_submaps");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(80, 60);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options = CoarseOptions();
  options.submaps.frames = 6;
  options.submaps.use = "always";
  options.submaps.render = 1;
  FusionScene fused(cam, options);
  scene::CaptureWriter keyframes(dir + "/keyframes", cam);
  scene::RgbdDataset frames;
  frames.camera = cam;
  const size_t n = sweep.size() / 8;
  for (size_t j = 0; j < n; ++j) {
    const size_t i = j * 8;
    scene::RgbdSample s = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
    s.id = "f" + std::to_string(i);
    // The second half's poses are recorded 6 cm off (a second capture that disagrees): its
    // submaps and the global TSDF then hold different surfaces.
    if (j >= n / 2)
      s.pose = scene::Pose(s.pose.translation() + Eigen::Vector3d(0.06, 0.0, 0.0), s.pose.rotation());
    fused.AddFrame(s);
    keyframes.Append(s);
    frames.frames.push_back(s);
  }
  REQUIRE(fused.submaps() != nullptr);
  REQUIRE(fused.submaps()->size() >= 3);
  FusionVersionInfo info;
  info.version = 1;
  info.frames_integrated = frames.frames.size();
  info.keyframes_dir = dir + "/keyframes";
  info.keyframe_count = frames.frames.size();
  const std::string version_dir = WriteSceneVersion(dir + "/versions", fused, info);
  const model::FusionVersionManifest m = model::ReadFusionVersion(version_dir);
  CHECK(m.submap_files.size() == fused.submaps()->size());
  CHECK(m.keyframe_submaps == fused.keyframe_submaps());
  CHECK(m.submap_frames == 6);

  FusionOptions plain;  // the caller's options have no submaps: the version's are restored
  plain.scene.submaps.render = 1;  // a view-time option: the caller's
  LoadedFusionVersion v = LoadFusionVersion(version_dir, plain, 48, 48);
  FusionScene& loaded = v.synthesizer->scene();
  REQUIRE(loaded.submaps() != nullptr);
  CHECK(loaded.submaps()->size() == fused.submaps()->size());
  CHECK(loaded.keyframe_submaps() == fused.keyframe_submaps());
  for (size_t i = 0; i < loaded.submaps()->size(); ++i)
    CHECK(loaded.submaps()->frames_in(i) == fused.submaps()->frames_in(i));

  // The same views as the scene it came from; a view from the global TSDF alone differs.
  FusionSynthesizer original(frames, FusionOptions{options, true}, v.synthesizer->Camera());
  FusionSceneOptions global_only = options;
  global_only.submaps.frames = 0;
  FusionSynthesizer global(frames, FusionOptions{global_only, true}, v.synthesizer->Camera());
  const scene::Pose pose = frames.frames[frames.frames.size() - 2].pose;
  const scene::RgbdSample a = v.synthesizer->Render(pose);
  const scene::RgbdSample b = original.Render(pose);
  const scene::RgbdSample g = global.Render(pose);
  CHECK(model::Psnr(a.rgb, b.rgb) > 35.0);
  CHECK(model::ComputeDepthErrors(a.depth, b.depth).abs_rel < 1e-3);
  INFO("global-only vs submaps: depth AbsRel " << model::ComputeDepthErrors(g.depth, b.depth).abs_rel);
  CHECK(model::ComputeDepthErrors(g.depth, b.depth).abs_rel > 5e-3);

  // A manifest whose keyframe submaps do not match its keyframes is refused, naming the fault.
  model::FusionVersionManifest bad = m;
  bad.keyframe_submaps.pop_back();
  CHECK_THROWS_WITH(model::FusionVersionManifest::FromJson(bad.ToJson(), "m.json"),
                    Catch::Contains("inconsistent submaps"));
  bad = m;
  bad.keyframe_submaps.back() = static_cast<int>(m.submap_files.size());
  CHECK_THROWS_WITH(model::FusionVersionManifest::FromJson(bad.ToJson(), "m.json"),
                    Catch::Contains("names no submap file"));
  fs::remove(fs::path(version_dir) / m.submap_files.back());
  CHECK_THROWS_WITH(LoadFusionVersion(version_dir, plain), Catch::Contains("submap file"));
}


TEST_CASE("fusion version: unchanged submaps are linked from the previous version, changed ones written",
          "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_io_reuse");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(64, 48);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options;
  options.tsdf.voxel_size_m = 0.04;
  options.tsdf.block_resolution = 8;
  options.submaps.frames = 3;
  options.submaps.use = "always";
  FusionScene fused(cam, options);
  scene::CaptureWriter keyframes(dir + "/keyframes", cam);
  size_t added = 0;
  auto add = [&](size_t n) {
    for (size_t j = 0; j < n; ++j, ++added) {
      const size_t i = added * 10;
      scene::RgbdSample s = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
      s.id = "f" + std::to_string(i);
      fused.AddFrame(s);
      keyframes.Append(s);
    }
  };
  auto info_for = [&](uint64_t version, const std::string& previous) {
    FusionVersionInfo info;
    info.version = version;
    info.frames_integrated = added;
    info.keyframes_dir = dir + "/keyframes";
    info.keyframe_count = added;
    info.previous_dir = previous;
    return info;
  };
  add(7);  // submaps of 3 + 3 + 1 frames
  const std::string v1 = WriteSceneVersion(dir + "/versions", fused, info_for(1, ""));
  add(1);  // the third submap grows: 3 + 3 + 2
  const std::string v2 = WriteSceneVersion(dir + "/versions", fused, info_for(2, v1));
  const model::FusionVersionManifest m1 = model::ReadFusionVersion(v1), m2 = model::ReadFusionVersion(v2);
  REQUIRE(m1.submap_files.size() == 3);
  REQUIRE(m2.submap_files.size() == 3);
  // The two finished submaps are the same files (hard links), the one that grew is new.
  for (size_t i = 0; i < 2; ++i) {
    CHECK(fs::equivalent(fs::path(v1) / m1.submap_files[i], fs::path(v2) / m2.submap_files[i]));
    CHECK(fs::hard_link_count(fs::path(v2) / m2.submap_files[i]) == 2);
  }
  CHECK_FALSE(fs::equivalent(fs::path(v1) / m1.submap_files[2], fs::path(v2) / m2.submap_files[2]));
  CHECK(fs::hard_link_count(fs::path(v2) / m2.submap_files[2]) == 1);

  // Built back, v2 renders as a version written from scratch does.
  const std::string fresh = WriteSceneVersion(dir + "/versions", fused, info_for(3, ""));
  CHECK(fs::hard_link_count(fs::path(fresh) / m2.submap_files[0]) == 1);
  const scene::Pose pose = sweep[35].pose;
  LoadedFusionVersion a = LoadFusionVersion(v2, FusionOptions{}, 48, 48);
  LoadedFusionVersion b = LoadFusionVersion(fresh, FusionOptions{}, 48, 48);
  const scene::RgbdSample ra = a.synthesizer->Render(pose), rb = b.synthesizer->Render(pose);
  CHECK(cv::norm(ra.rgb, rb.rgb, cv::NORM_INF) == 0.0);
  CHECK(cv::norm(ra.depth, rb.depth, cv::NORM_INF) == 0.0);

  // The previous version pruned (or never there): every submap is written, nothing fails.
  fs::remove_all(v1);
  const std::string v4 = WriteSceneVersion(dir + "/versions", fused, info_for(4, v1));
  for (const std::string& f : model::ReadFusionVersion(v4).submap_files)
    CHECK(fs::hard_link_count(fs::path(v4) / f) == 1);
  // Linked files outlive the version they came from: v2 still loads after v1 is gone.
  CHECK_NOTHROW(LoadFusionVersion(v2, FusionOptions{}, 48, 48));
}

TEST_CASE("fusion version: per-capture submaps (the default) are saved from the second capture on",
          "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_io_captures");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(80, 60);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options = CoarseOptions();  // submaps: {frames: capture, use: auto}
  FusionScene fused(cam, options);
  scene::CaptureWriter keyframes(dir + "/keyframes", cam);
  const size_t n = sweep.size() / 8;
  FusionVersionInfo info;
  info.keyframes_dir = dir + "/keyframes";
  std::string one_capture;
  for (size_t j = 0; j < n; ++j) {
    const size_t i = j * 8;
    scene::RgbdSample s = sim.Render(sweep[i].pose, cam, sweep[i].stamp);
    s.id = "f" + std::to_string(i);
    if (j == n / 2) {  // one capture so far: a version holds the global TSDF alone
      info.version = 1;
      info.frames_integrated = info.keyframe_count = j;
      one_capture = WriteSceneVersion(dir + "/versions", fused, info);
    }
    // The second half is a second capture whose poses are recorded 0.6 m off: a pose jump.
    if (j >= n / 2)
      s.pose = scene::Pose(s.pose.translation() + Eigen::Vector3d(0.6, 0.0, 0.0), s.pose.rotation());
    fused.AddFrame(s);
    keyframes.Append(s);
  }
  const model::FusionVersionManifest first = model::ReadFusionVersion(one_capture);
  CHECK(first.submap_files.empty());
  REQUIRE(fused.submaps()->size() == 2);
  CHECK(fused.submaps()->frames_in(0) == static_cast<int>(n / 2));
  info.version = 2;
  info.frames_integrated = info.keyframe_count = n;
  const std::string two_captures = WriteSceneVersion(dir + "/versions", fused, info);
  const model::FusionVersionManifest m = model::ReadFusionVersion(two_captures);
  CHECK(m.submap_files.size() == 2);
  CHECK(m.submap_frames == SubmapOptions::kCapture);
  CHECK(m.keyframe_submaps == fused.keyframe_submaps());

  LoadedFusionVersion v = LoadFusionVersion(two_captures, FusionOptions{}, 48, 48);
  FusionScene& loaded = v.synthesizer->scene();
  REQUIRE(loaded.submaps() != nullptr);
  CHECK(loaded.submaps()->size() == 2);
  CHECK(loaded.submaps()->options().per_capture());
  CHECK(loaded.submap_choice().submaps == 2);  // chosen again at the load
  CHECK(loaded.submap_choice().frames > 0);
  CHECK(loaded.uses_submaps());  // the second capture lies 0.6 m off: the submaps pay
  CHECK_THAT(loaded.AutoChoices(), Catch::Contains("submaps auto: "));
  LoadedFusionVersion single = LoadFusionVersion(one_capture, FusionOptions{}, 48, 48);
  CHECK(single.synthesizer->scene().submaps()->size() == 0);
  CHECK_FALSE(single.synthesizer->scene().uses_submaps());
}

TEST_CASE("fusion version: a snapshot writes the scene as it was when taken, while the scene goes on",
          "[unit]") {
  const std::string dir = p2i::testing::FreshDir("fusion_version_snapshot");
  const auto sim = scene::SimScene::BuiltIn("small_office");
  const scene::CameraInfo cam = scene::SimScene::DefaultCamera(80, 60);
  const auto sweep = scene::GenerateArmSweep({});
  FusionSceneOptions options = CoarseOptions();
  FusionScene fused(cam, options);
  scene::CaptureWriter keyframes(dir + "/keyframes", cam);
  std::vector<scene::RgbdSample> frames;
  for (size_t i = 0; i < sweep.size(); i += 8) frames.push_back(sim.Render(sweep[i].pose, cam, sweep[i].stamp));
  const size_t half = frames.size() / 2;
  for (size_t i = 0; i < half; ++i) {
    fused.AddFrame(frames[i]);
    keyframes.Append(frames[i]);
  }
  FusionVersionInfo info;
  info.version = 1;
  info.frames_integrated = half;
  info.keyframes_dir = dir + "/keyframes";
  info.keyframe_count = half;
  const SceneVersionSnapshot snapshot = SnapshotSceneVersion(dir + "/versions", fused, info);
  info.version = 2;
  const std::string direct = WriteSceneVersion(dir + "/versions", fused, info);  // the same moment
  for (size_t i = half; i < frames.size(); ++i) fused.AddFrame(frames[i]);     // the scene goes on
  const std::string written = WriteSceneVersion(snapshot);
  CHECK(fs::path(written).filename() == "fusion_v000001");
  CHECK(model::ReadFusionVersion(written).frames_integrated == half);

  // The snapshot's TSDF is the scene's at the snapshot: as the direct write's, short of the frames
  // integrated after it.
  const TsdfOptions tsdf = fused.tsdf().options();
  TsdfVolume from_snapshot = TsdfVolume::Load(written + "/tsdf.npz", tsdf);
  TsdfVolume from_direct = TsdfVolume::Load(direct + "/tsdf.npz", tsdf);
  const scene::Pose late = frames.back().pose;
  const cv::Mat a = from_snapshot.Raycast(late, cam).depth, b = from_direct.Raycast(late, cam).depth;
  CHECK(cv::norm(a, b, cv::NORM_INF) < 1e-6);
  CHECK(from_snapshot.Stats().blocks == from_direct.Stats().blocks);
  CHECK(from_snapshot.Stats().blocks < fused.tsdf().Stats().blocks);
  CHECK(cv::countNonZero(a) < cv::countNonZero(fused.tsdf().Raycast(late, cam).depth));

  // It builds like any version.
  LoadedFusionVersion v = LoadFusionVersion(written, FusionOptions{});
  CHECK(v.synthesizer->scene().keyframes().size() == half);
  CHECK_THROWS_WITH(WriteSceneVersion(SceneVersionSnapshot{}), Catch::Contains("empty snapshot"));
}

}  // namespace p2i::fusion
