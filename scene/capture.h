/// @file capture.h
/// @brief The p2i capture folder (docs/DATASETS.md): written frame by frame, atomically, so a
/// killed writer leaves a readable dataset.
#pragma once

#include <string>
#include <vector>

#include "scene/dataset_index.h"

namespace p2i::scene {

/// Writes `bytes` to `path` through a temporary file in the same folder and rename(2), so readers
/// see the old file or the new one, never a partial one. With `sync` the data is fsync-ed before
/// the rename (survives power loss, not only process kills). Throws std::runtime_error naming
/// the file on an I/O error.
void WriteFileAtomic(const std::string& path, const std::string& bytes, bool sync = false);

/// Writes one p2i capture folder:
///   FOLDER/manifest.yaml       format, version, files, depth encoding, the list of frames
///   FOLDER/camera_info.yaml    ROS camera_info
///   FOLDER/poses.txt           TUM trajectory, one line per listed frame, same order
///   FOLDER/rgb/NNNNNN.png      8-bit RGB
///   FOLDER/depth/NNNNNN.png    16-bit millimetres, 0 = invalid
/// Append() writes the two images (each temp + rename), then poses.txt, then the manifest (each
/// temp + rename): the manifest is the commit point, so a frame is listed only once all its files
/// are complete. Rewriting the lists costs O(frames) per frame: fine for the tens of thousands of
/// frames of a capture. Not thread-safe: one writer per folder (a second writer is not detected).
class CaptureWriter {
 public:
  struct Options {
    /// Existing manifest in the folder: false = error, true = start a new, empty capture.
    bool overwrite = false;
    /// fsync every file before its rename (slower; protects against power loss too).
    bool sync = false;
  };

  /// Creates the folder (and parents) and writes camera_info.yaml and an empty manifest.
  /// Throws std::runtime_error when the folder already holds a capture and !overwrite.
  CaptureWriter(const std::string& folder, const CameraInfo& camera, const Options& options);
  CaptureWriter(const std::string& folder, const CameraInfo& camera)
      : CaptureWriter(folder, camera, Options()) {}

  /// Writes and lists one frame. rgb must be CV_8UC3 (RGB order), depth CV_32FC1 metres, both of
  /// the camera's size (else std::invalid_argument). Depth is stored in whole millimetres.
  void Append(const RgbdSample& sample);

  size_t size() const { return count_; }
  const std::string& folder() const { return folder_; }

 private:
  void Commit();

  std::string folder_;
  CameraInfo camera_;
  Options options_;
  size_t count_ = 0;
  std::string manifest_frames_;  ///< the manifest's frame lines written so far
  std::string poses_;            ///< poses.txt so far
};

/// Reads a p2i capture folder: only frames listed in manifest.yaml, with their poses from
/// poses.txt. The sequence is the folder's name; ids are "<sequence>/NNNNNN". Throws
/// std::runtime_error naming the file and problem (no manifest, unknown format or version,
/// unknown key, a pose missing or with a different stamp, a listed image file missing).
DatasetIndex ReadCapture(const std::string& folder);

/// True when `folder` holds a manifest.yaml of format p2i_capture.
bool IsCaptureFolder(const std::string& folder);

}  // namespace p2i::scene
