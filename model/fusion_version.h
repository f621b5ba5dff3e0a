/// @file fusion_version.h
/// @brief One published model version of the `fusion` method on disk: a folder holding the TSDF
/// snapshot, the refinement weights and a manifest, committed by one rename so a reader sees a
/// whole version or none. Torch-free (the trainer node writes versions, the synthesizer reads
/// them).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace p2i::model {

/// manifest.json of a version folder.
///
/// Keyframes are not copied into every version: they live in the trainer's append-only p2i
/// capture folder `keyframes_dir` (scene::CaptureWriter commits each frame atomically), and a
/// version uses its first `keyframe_count` listed frames. A version therefore references only
/// frames that were committed before it.
struct FusionVersionManifest {
  uint64_t version = 0;
  int64_t step = 0;                  ///< refinement optimiser steps so far
  uint64_t frames_integrated = 0;    ///< camera frames fused into the TSDF snapshot
  std::string tsdf_file = "tsdf.npz";      ///< relative to the version folder
  std::string refine_file = "refine.pt";   ///< relative to the version folder ("" = no refinement)
  std::string keyframes_dir;         ///< absolute path of the keyframe capture folder
  uint64_t keyframe_count = 0;
  int width = 0;                     ///< rendered view size
  int height = 0;
  double voxel_size_m = 0.0;         ///< of the TSDF snapshot (fusion::TsdfOptions::voxel_size_m)
  int block_resolution = 16;         ///< of the TSDF snapshot (fusion::TsdfOptions::block_resolution)
  double trunc_voxels = 4.0;         ///< of the TSDF snapshot (fusion::TsdfOptions::trunc_voxels)
  /// Local submaps (fusion::SubmapOptions; all empty = one global TSDF): one TSDF file per
  /// submap (relative to the version folder, same voxel size as tsdf_file), the frames fused into
  /// each, the submap of each of the keyframe_count keyframes (-1 = none), and the option
  /// `frames` they were cut with (2147483647: one per capture, fusion::SubmapOptions::kCapture;
  /// a version of a single capture has none: its frames are the global TSDF's).
  std::vector<std::string> submap_files;
  std::vector<int> submap_frame_counts;
  std::vector<int> keyframe_submaps;
  int submap_frames = 0;
  double val_psnr = 0.0;             ///< held-out (leave-one-out) PSNR of the refined view, dB
  double val_psnr_blend = 0.0;       ///< same frames, plain blend, dB

  std::string ToJson() const;
  /// Throws std::runtime_error naming `source` on bad JSON or missing keys.
  static FusionVersionManifest FromJson(const std::string& json, const std::string& source);
};

/// `versions_dir/fusion_vNNNNNN` (absolute).
std::string FusionVersionDir(const std::string& versions_dir, uint64_t version);

/// Writes a version folder atomically: makes `final_dir + ".tmp.<pid>"`, calls
/// `write_payload(temp_dir)` (which writes the TSDF and the refinement file there), writes
/// manifest.json, fsyncs the files and the folder, then renames the folder to `final_dir`
/// (which must not exist). A throw or a kill before the rename leaves no `final_dir`; the temp
/// folder is removed on a throw (and by RemoveStaleVersionTemps after a kill). Throws
/// std::runtime_error naming the folder.
void WriteFusionVersion(const std::string& final_dir, const FusionVersionManifest& manifest,
                        const std::function<void(const std::string& temp_dir)>& write_payload);

/// Reads and checks a version folder: manifest.json parses, the TSDF and refinement files it
/// names exist, and the keyframe folder exists. Throws std::runtime_error naming the folder and
/// what is missing.
FusionVersionManifest ReadFusionVersion(const std::string& dir);

/// Versions in `versions_dir` (committed folders only), ascending.
std::vector<uint64_t> ListFusionVersions(const std::string& versions_dir);

/// Removes `*.tmp.*` folders left by a killed writer, and all but the newest `keep` committed
/// versions (keep >= 1), except those committed less than `min_age_s` seconds ago (by the
/// folder's modification time): a reader that was told of a version a moment ago (a synthesizer
/// loading it on a busy machine) still finds it. Returns the number of folders removed.
int PruneFusionVersions(const std::string& versions_dir, int keep, double min_age_s = 0.0);

}  // namespace p2i::model
