/// @file fusion_version_io.h
/// @brief The `fusion` method's published model versions (model/fusion_version.h) from the
/// fusion side: the online mapper (the trainer node with method fusion) writes a FusionScene's
/// TSDF as a version; the synthesizer builds a FusionSynthesizer from one. Torch-free: the
/// refinement file a version may name is loaded by the caller (refine/fusion_method.cc).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

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
