/// @file fusion_version_io.h
/// @brief The `fusion` method's published model versions (model/fusion_version.h) from the
/// fusion side: the online mapper (the trainer node with method fusion) writes a FusionScene's
/// TSDF as a version; the synthesizer builds a FusionSynthesizer from one. Torch-free: the
/// refinement file a version may name is loaded by the caller (refine/fusion_method.cc).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fusion/fusion_synthesizer.h"
#include "model/fusion_version.h"

namespace p2i::fusion {

/// What the mapper knows about the version it writes, beside the scene.
struct FusionVersionInfo {
  uint64_t version = 0;
  uint64_t frames_integrated = 0;
  std::string keyframes_dir;    ///< the mapper's append-only keyframe capture folder
  uint64_t keyframe_count = 0;  ///< its first frames that belong to this version
  std::string refine_source;    ///< a refinement file copied into the version ("" = none)
  int64_t refine_steps = 0;     ///< optimiser steps it has seen (the manifest's `step`)
  /// A version folder this writer committed earlier from the same scene ("" = none). A submap
  /// with the same index and frame count there is unchanged (a submap changes only by fusing a
  /// frame), so its file is hard-linked from it instead of written again; any failure to read or
  /// link falls back to writing it.
  std::string previous_dir;
};

/// Writes `scene`'s TSDF (and the refinement file, when named) as the committed version folder
/// model::FusionVersionDir(versions_dir, info.version), atomically (model::WriteFusionVersion),
/// reusing info.previous_dir's unchanged submap files. Returns the folder. Throws std::runtime_error naming the folder.
std::string WriteSceneVersion(const std::string& versions_dir, FusionScene& scene,
                              const FusionVersionInfo& info);

/// A FusionScene's version taken at one moment, to be written later (on another thread) while
/// the scene takes more frames: its manifest and copies (TsdfVolume::Clone: milliseconds in 8^3
/// blocks, where writing the file takes ~0.5 s for a room) of the volumes whose files change. A
/// submap unchanged since info.previous_dir is linked from there when written, not copied.
struct SceneVersionSnapshot {
  std::string versions_dir;
  FusionVersionInfo info;
  model::FusionVersionManifest manifest;
  std::vector<std::string> reusable;   ///< per submap: the previous version's file, or ""
  std::unique_ptr<TsdfVolume> tsdf;    ///< copy of the global TSDF
  std::vector<std::unique_ptr<TsdfVolume>> submaps;  ///< copies (null where reusable is set)
};

/// Takes the snapshot WriteSceneVersion(snapshot) writes: what WriteSceneVersion(versions_dir,
/// scene, info) would write now. The scene is read, not changed.
SceneVersionSnapshot SnapshotSceneVersion(const std::string& versions_dir, FusionScene& scene,
                                          const FusionVersionInfo& info);

/// Writes a snapshot as WriteSceneVersion(versions_dir, scene, info) writes the scene (same
/// folder, same files). Safe on any thread: it touches nothing but the snapshot. Throws
/// std::runtime_error naming the folder, or a submap whose previous file can no longer be linked
/// (a version pruned between the snapshot and the write).
std::string WriteSceneVersion(const SceneVersionSnapshot& snapshot);

/// A built version: the synthesizer and the manifest it came from.
struct LoadedFusionVersion {
  std::unique_ptr<FusionSynthesizer> synthesizer;
  model::FusionVersionManifest manifest;
  std::string refine_path;  ///< absolute path of the version's refinement file, "" = none
};

/// Builds the `fusion` method from the version folder `dir`: its TSDF snapshot (voxel size,
/// block resolution and truncation from the manifest, the rest of `options` the caller's) and
/// the first keyframe_count frames of its keyframe capture as colour sources (not re-fused;
/// every one kept). Output camera: the keyframes' camera centre-cropped and resized to width x
/// height (0 x 0 = their own). The volume is prepared (TsdfVolume::Prepare: the mesh is built
/// here, in the caller's thread). No refiner is set. Throws std::runtime_error naming the folder
/// and what is missing (manifest, TSDF, keyframes).
LoadedFusionVersion LoadFusionVersion(const std::string& dir, FusionOptions options, int width = 0,
                                      int height = 0);

}  // namespace p2i::fusion
