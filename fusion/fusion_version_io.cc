/// @file fusion_version_io.cc
/// @brief Writing a FusionScene as a fusion version, and building the method from one.
#include "fusion/fusion_version_io.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "scene/capture.h"
#include "scene/image_ops.h"

namespace p2i::fusion {

namespace fs = std::filesystem;

namespace {

/// Per submap of `m`: the file of the same submap in the version folder `previous` when it holds
/// the same number of frames there (unchanged since), else "". All "" without a readable
/// previous version.
std::vector<std::string> UnchangedSubmapFiles(const std::string& previous,
                                              const model::FusionVersionManifest& m) {
  std::vector<std::string> out(m.submap_files.size());
  if (previous.empty()) return out;
  model::FusionVersionManifest p;
  try {
    p = model::ReadFusionVersion(previous);
  } catch (const std::exception&) {
    return out;  // pruned or unreadable: every submap is written
  }
  if (p.voxel_size_m != m.voxel_size_m || p.block_resolution != m.block_resolution ||
      p.trunc_voxels != m.trunc_voxels)
    return out;
  for (size_t i = 0; i < out.size() && i < p.submap_files.size(); ++i) {
    if (i >= p.submap_frame_counts.size() || p.submap_frame_counts[i] != m.submap_frame_counts[i])
      continue;
    const fs::path file = fs::path(previous) / p.submap_files[i];
    std::error_code ec;
    if (fs::is_regular_file(file, ec)) out[i] = file.string();
  }
  return out;
}

}  // namespace

namespace {

/// The manifest of `scene` as a version described by `info`.
model::FusionVersionManifest SceneManifest(FusionScene& scene, const FusionVersionInfo& info) {
  const TsdfOptions& tsdf = scene.options().tsdf;
  model::FusionVersionManifest m;
  m.version = info.version;
  m.frames_integrated = info.frames_integrated;
  m.keyframes_dir = fs::absolute(info.keyframes_dir).string();
  m.keyframe_count = info.keyframe_count;
  m.width = scene.frame_camera().image_width;
  m.height = scene.frame_camera().image_height;
  m.voxel_size_m = tsdf.voxel_size_m;
  m.block_resolution = tsdf.block_resolution;
  m.trunc_voxels = tsdf.trunc_voxels;
  m.refine_file = info.refine_source.empty() ? "" : "refine.pt";
  m.step = info.refine_steps;
  if (const SubmapSet* sub = scene.submaps()) {
    for (size_t i = 0; i < sub->size(); ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "submap_%04zu.npz", i);
      m.submap_files.push_back(name);
      m.submap_frame_counts.push_back(sub->frames_in(i));
    }
    const std::vector<int>& ks = scene.keyframe_submaps();
    m.keyframe_submaps.assign(ks.begin(), ks.begin() + static_cast<std::ptrdiff_t>(
                                                           std::min<size_t>(ks.size(), info.keyframe_count)));
    m.submap_frames = sub->options().frames;
    if (m.submap_files.empty()) m.keyframe_submaps.clear();  // no frame fused yet: none to save
  }
  return m;
}

/// Commits the version folder of `m` under `versions_dir`: the global TSDF, each submap (linked
/// from `reusable[i]` when set, else `submap(i)` written) and the refinement file.
template <typename SubmapVolume>
std::string CommitVersion(const std::string& versions_dir, const model::FusionVersionManifest& m,
                          const std::vector<std::string>& reusable, const TsdfVolume& tsdf,
                          SubmapVolume submap, const std::string& refine_source) {
  const std::string dir = model::FusionVersionDir(versions_dir, m.version);
  fs::create_directories(versions_dir);
  model::WriteFusionVersion(dir, m, [&](const std::string& temp) {
    tsdf.Save(temp + "/" + m.tsdf_file);
    for (size_t i = 0; i < m.submap_files.size(); ++i) {
      const std::string to = temp + "/" + m.submap_files[i];
      std::error_code ec;
      if (!reusable[i].empty()) fs::create_hard_link(reusable[i], to, ec);
      if (reusable[i].empty() || ec) submap(i).Save(to);
    }
    if (!refine_source.empty()) fs::copy_file(refine_source, temp + "/" + m.refine_file);
  });
  return dir;
}

}  // namespace

std::string WriteSceneVersion(const std::string& versions_dir, FusionScene& scene,
                              const FusionVersionInfo& info) {
  const model::FusionVersionManifest m = SceneManifest(scene, info);
  return CommitVersion(versions_dir, m, UnchangedSubmapFiles(info.previous_dir, m), scene.tsdf(),
                       [&](size_t i) -> const TsdfVolume& { return scene.submaps()->volume(i); },
                       info.refine_source);
}

SceneVersionSnapshot SnapshotSceneVersion(const std::string& versions_dir, FusionScene& scene,
                                          const FusionVersionInfo& info) {
  SceneVersionSnapshot s;
  s.versions_dir = versions_dir;
  s.info = info;
  s.manifest = SceneManifest(scene, info);
  s.reusable = UnchangedSubmapFiles(info.previous_dir, s.manifest);
  s.tsdf = std::make_unique<TsdfVolume>(scene.tsdf().Clone());
  s.submaps.resize(s.manifest.submap_files.size());
  for (size_t i = 0; i < s.submaps.size(); ++i)
    if (s.reusable[i].empty()) s.submaps[i] = std::make_unique<TsdfVolume>(scene.submaps()->volume(i).Clone());
  return s;
}

std::string WriteSceneVersion(const SceneVersionSnapshot& snapshot) {
  if (!snapshot.tsdf) throw std::invalid_argument("WriteSceneVersion: an empty snapshot");
  return CommitVersion(
      snapshot.versions_dir, snapshot.manifest, snapshot.reusable, *snapshot.tsdf,
      [&](size_t i) -> const TsdfVolume& {
        // A linked file that turns out unreadable at commit time has no copy to fall back on.
        if (!snapshot.submaps[i])
          throw std::runtime_error("fusion version " + std::to_string(snapshot.manifest.version) +
                                   ": submap file " + snapshot.reusable[i] +
                                   " could not be linked and no copy was taken");
        return *snapshot.submaps[i];
      },
      snapshot.info.refine_source);
}

LoadedFusionVersion LoadFusionVersion(const std::string& dir, FusionOptions options, int width,
                                      int height) {
  LoadedFusionVersion out;
  out.manifest = model::ReadFusionVersion(dir);
  const model::FusionVersionManifest& m = out.manifest;
  TsdfOptions& tsdf = options.scene.tsdf;
  tsdf.voxel_size_m = m.voxel_size_m;
  tsdf.block_resolution = m.block_resolution;
  tsdf.trunc_voxels = m.trunc_voxels;
  options.scene.blend.keyframe_min_distance = 0.0;  // the mapper chose them
  try {
    options.Validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("fusion version " + dir + ": " + e.what());
  }
  const scene::DatasetIndex keyframes = scene::ReadCapture(m.keyframes_dir);
  if (keyframes.size() < m.keyframe_count) {
    throw std::runtime_error("fusion version " + dir + ": its keyframe folder " + m.keyframes_dir +
                             " lists " + std::to_string(keyframes.size()) + " frames, the version " +
                             "needs " + std::to_string(m.keyframe_count) +
                             " (the folder was replaced or truncated)");
  }
  scene::RgbdDataset empty;
  empty.camera = keyframes.camera();
  const scene::CameraInfo output =
      width > 0 && height > 0 ? scene::CenterCropResizeCamera(empty.camera, width, height)
                              : empty.camera;
  out.synthesizer = std::make_unique<FusionSynthesizer>(empty, options, output);
  FusionScene& fused = out.synthesizer->scene();
  fused.tsdf() = TsdfVolume::Load((fs::path(dir) / m.tsdf_file).string(), tsdf);
  for (size_t i = 0; i < m.keyframe_count; ++i) fused.AddFrame(keyframes.Load(i), /*integrate=*/false);
  if (!m.submap_files.empty()) {
    SubmapOptions sub = options.scene.submaps;
    sub.frames = m.submap_frames;
    SubmapSet set(sub, tsdf);
    for (size_t i = 0; i < m.submap_files.size(); ++i)
      set.Append(TsdfVolume::Load((fs::path(dir) / m.submap_files[i]).string(), tsdf),
                 m.submap_frame_counts[i]);
    fused.RestoreSubmaps(std::move(set), m.keyframe_submaps);
  }
  fused.Prepare();  // the meshes now, in the loader's thread, not in the first view
  if (const std::string chosen = fused.AutoChoices(); !chosen.empty())
    std::fprintf(stderr, "fusion version %s: %s\n", dir.c_str(), chosen.c_str());
  if (!m.refine_file.empty()) out.refine_path = fs::absolute(fs::path(dir) / m.refine_file).string();
  return out;
}

}  // namespace p2i::fusion
