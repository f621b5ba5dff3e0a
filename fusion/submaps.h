/// @file submaps.h
/// @brief Local TSDF submaps: the frames of one stretch of the trajectory fused on their own, so a
/// view is rendered from geometry whose poses agree with the keyframes that colour it. Poses that
/// drift over a long capture, or two captures whose poses disagree where they overlap, make one
/// global TSDF average surfaces that are off by centimetres; the keyframes of either capture then
/// project their colours onto the wrong place (docs/RESULTS.md "One capture at a time").
#pragma once

#include <string>
#include <vector>

#include "fusion/tsdf_volume.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::fusion {

struct SubmapOptions {
  /// `frames: capture`: a submap per capture, ended only by a pose jump.
  static constexpr int kCapture = 2147483647;
  /// Frames fused into one submap before the next one starts (0 = no submaps: one global TSDF;
  /// kCapture, YAML "capture" = one per capture). Per-capture submaps start lazily: while there
  /// is one capture its frames are the global TSDF's, and no submap is kept; at the first pose
  /// jump a copy of the global TSDF becomes the first capture's submap (SubmapSet::Integrate).
  int frames = 0;
  /// A frame whose pose jumps this far from the previous frame's (metres, or degrees) starts a new
  /// submap: the next capture, or a relocalisation.
  double break_m = 0.5;
  double break_deg = 45.0;
  /// A view is raycast in the submaps of its nearest keyframe slots, nearest first, at most this
  /// many; each fills the pixels the previous ones left without a surface. The global TSDF (every
  /// frame) fills what is left.
  int render = 2;
  /// Whether views use the submaps: "always", or "auto": only where a leave-one-out on the
  /// keyframes shows they pay (ChooseSubmaps, submap_choice.h), chosen at every
  /// FusionScene::Prepare; until then, and where they do not pay, views use the global TSDF.
  std::string use = "always";
  /// Reads {frames, break_m, break_deg, render, use} (all optional) over the fusion default
  /// (PerCaptureAuto), then Validate(). `frames: N` (a count) without `use` is used always, as
  /// submaps by count were before `use` existed; `frames: 0` turns the submaps off. Unknown keys and
  /// bad values throw std::runtime_error naming `source`, the line and the key.
  static SubmapOptions FromYaml(const YAML::Node& node, const std::string& source);
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
  bool enabled() const { return frames > 0; }
  /// The `fusion` method's default: a submap per capture, used where a leave-one-out shows they
  /// pay (one capture keeps none: its frames are the global TSDF's).
  static SubmapOptions PerCaptureAuto() {
    SubmapOptions o;
    o.frames = kCapture;
    o.use = "auto";
    return o;
  }
  bool per_capture() const { return frames == kCapture; }
  /// "capture", or the frame count.
  std::string DescribeFrames() const;
};

/// The submaps of a growing capture. Frames arrive in capture order (Integrate); each goes into
/// the current submap, which ends after SubmapOptions::frames frames or at a pose jump.
/// Thread-compatible, like TsdfVolume.
class SubmapSet {
 public:
  SubmapSet(SubmapOptions options, TsdfOptions tsdf);

  /// Fuses the frame into the current submap (starting a new one first when due) and returns that
  /// submap's index. The submap a new one replaces never changes again: it is prepared
  /// (TsdfVolume::Prepare) here, so no view pays for its mesh.
  /// Per capture (SubmapOptions::per_capture) while no submap exists: the frame is the global
  /// TSDF's alone (returns -1) until a pose jump; then a copy of `global` (which must hold
  /// exactly the frames passed so far, not yet this one) becomes submap 0 and the frame starts
  /// submap 1. `global` may be null otherwise.
  int Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera,
                const TsdfVolume* global = nullptr);
  /// Whether the next Integrate of a frame at `pose` reads `global` or keeps the frame out of the
  /// submaps (per capture, no submap yet): the caller must then integrate the global TSDF after
  /// it, not beside it.
  bool Deferring() const { return options_.per_capture() && maps_.empty(); }

  /// Appends a finished submap (one loaded from a saved version, `frames` its frame count). The
  /// next Integrate starts a new submap after it.
  void Append(TsdfVolume volume, int frames);

  /// Prepares every submap (TsdfVolume::Prepare): a loader calls it so views do not build meshes.
  void Prepare();

  /// Index of the submap the next frame would go to when it continues the current one (the last
  /// one), -1 before the first frame.
  int current() const { return static_cast<int>(maps_.size()) - 1; }
  size_t size() const { return maps_.size(); }
  int frames_in(size_t i) const { return maps_.at(i).frames; }
  const TsdfVolume& volume(size_t i) const { return maps_.at(i).volume; }
  const SubmapOptions& options() const { return options_; }

  /// Raycasts the submaps `order` (indices, nearest first; duplicates and -1 are skipped, at most
  /// SubmapOptions::render of them) and merges them: each pixel takes the first submap with a
  /// surface there. `*from` (optional, CV_8UC1) gets, per pixel, 1 + the position in `order` of
  /// the submap it came from, 0 = none.
  TsdfRaycast Raycast(const std::vector<int>& order, const scene::Pose& pose,
                      const scene::CameraInfo& camera, cv::Mat* from = nullptr);

  /// Memory and blocks summed over the submaps (frames: frames fused).
  TsdfStats Stats() const;

 private:
  struct Map {
    TsdfVolume volume;
    int frames = 0;
  };
  SubmapOptions options_;
  TsdfOptions tsdf_;
  std::vector<Map> maps_;
  scene::Pose last_pose_;  ///< of the last frame integrated (valid unless sealed_)
  bool sealed_ = false;    ///< the last submap was appended (Append): the next frame starts one
  int deferred_ = 0;       ///< per capture: frames passed before the first submap (the global's)
};

/// Pixels of `into` without a surface (depth 0) take depth, normal and colour from `from`.
/// Returns how many were filled.
int64_t FillMissingSurface(TsdfRaycast* into, const TsdfRaycast& from);

/// Pixels of `into` (a view at `pose` through `camera`) without a surface take it from `volume`,
/// raycast only through the bounding rectangle of those pixels; a mesh surface draws only the
/// missing pixels themselves (chunks and triangles over pixels that have one are skipped). `*filled` (optional, CV_8UC1 of the view's size) gets 255 where a pixel was
/// filled. Returns how many were; 0 without a raycast when none is missing.
int64_t FillMissingFrom(TsdfVolume& volume, const scene::Pose& pose, const scene::CameraInfo& camera,
                        TsdfRaycast* into, cv::Mat* filled = nullptr);

}  // namespace p2i::fusion
