/// @file fusion_scene.h
/// @brief The fused scene of the `fusion` method: a TSDF of every frame added (geometry) plus the
/// keyframes whose colours are blended onto the raycast surface (appearance), rendering the
/// per-view candidates of view_candidates.h at any pose and camera.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fusion/align_choice.h"
#include "fusion/depth_choice.h"
#include "fusion/slot_alignment.h"
#include "fusion/submap_choice.h"
#include "fusion/submaps.h"
#include "fusion/tsdf_volume.h"
#include "fusion/view_candidates.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::fusion {

/// Keyframe selection and view-dependent blending (unstructured lumigraph rendering, Buehler et
/// al. 2001, with a per-view keyframe set).
struct BlendOptions {
  int k = 4;                        ///< keyframe slots per view
  double metres_per_degree = 0.01;  ///< rotation weight of the keyframe choice (coverage.h)
  /// Visibility: a keyframe sees a surface point when its own depth at the projection is within
  /// max(visibility_abs_m, visibility_rel * z) of the point's depth in that keyframe.
  double visibility_abs_m = 0.03;
  double visibility_rel = 0.03;
  /// Penalty of slot j at a pixel: ray angle (radians) + resolution_weight * max(0, (|X - C_j| -
  /// |X - C|) / |X - C|) (a keyframe farther from the point than the requested camera sees it
  /// blurrier). Weight: (1 - p / p_max)^2 / (p + penalty_epsilon), p_max = 1.5 x the largest
  /// visible penalty (so the worst visible slot keeps a small weight, the best dominates, and a
  /// keyframe exactly at the requested ray wins outright).
  double resolution_weight = 0.5;
  double penalty_epsilon = 1e-3;
  /// Grazing: the weight is multiplied by max(cos(normal, keyframe ray), grazing_floor).
  double grazing_floor = 0.1;
  /// Confidence = exp(-(smallest visible ray angle / angle_sigma_deg)^2) x grazing factor.
  double angle_sigma_deg = 15.0;
  /// A new frame becomes a keyframe only when its pose is at least this far (CombinedPoseDistance)
  /// from every keyframe (0 = every frame is a keyframe; the TSDF always gets every frame).
  double keyframe_min_distance = 0.0;
  /// How a keyframe's colour is read at a surface point's projection (keyframe_sampling.h):
  /// "bicubic" (Keys' cubic, cubic_a below; sharper), "bilinear", or "auto" (the default since
  /// 2026-12-04): bicubic where the view reads its pyramid level at about one level pixel per
  /// view pixel, bilinear where it skips pixels of the level (UseBicubicRead, keyframe_pyramid.h).
  std::string sampling = "auto";
  /// The bicubic read's kernel: Keys' cubic convolution with this parameter, in [-1, 0]. -0.75
  /// (the default since session 50, OpenCV's INTER_CUBIC) keeps more of the detail between pixels
  /// than -0.5 (Catmull-Rom, the kernel before; exact on linear ramps, where -0.75 reads up to
  /// ~0.04 px off): LPIPS 0.002-0.004 lower on both sims and study-room, PSNR and SSIM level
  /// (docs/RESULTS.md "A sharper bicubic read").
  double cubic_a = -0.75;
  /// Pre-filtered half, quarter, ... copies of each keyframe's colour kept for views rendered
  /// below the camera's resolution (keyframe_pyramid.h): a view reads the level nearest at or
  /// above its own focal length, at most this many halvings down (0 = always read the keyframe
  /// itself, unfiltered). A view at the camera's resolution reads the keyframe either way.
  int keyframe_levels = 3;
  /// Pixels whose ray finds no fused surface (beyond the depth sensor's range, windows, dropout)
  /// take their colour from the slots as if the scene were this far along the ray, from the slots
  /// that saw nothing nearer than 0.8 x this there (their own depth invalid or beyond it); depth
  /// stays 0 (no geometry), ViewCandidates::far marks them. 0 = off (they stay holes for the
  /// hole fill). Default: the TSDF's default depth_max_m.
  double far_depth_m = 5.0;
  /// The view's depth where slots see its surface: "raycast" (the TSDF's surface; the default
  /// until session 46), "keyframes" (the blend-weighted depth of the slots' own depth maps there,
  /// each slot's measured point on its own ray taken to the view's z, as depth warp's depth is;
  /// the raycast stays where no slot sees the surface), or "auto" (the default since session 46):
  /// whichever of the two reproduces held-out keyframes' own depth better (ChooseDepthSource,
  /// depth_choice.h), chosen again at every FusionScene::Prepare. Keyframe depth wins on real
  /// sensors (a per-pixel bias shared by nearby frames), the raycast where depth noise is
  /// zero-mean (the sim).
  std::string depth = "auto";
  /// Edge-preserving smoothing of each keyframe's colour before the blend reads it: a 5x5
  /// bilateral filter (spatial sigma 1 px) whose colour sigma is this many 8-bit grey levels
  /// (0 = off, the default; about 3x the camera's RGB noise sigma). The blend weights its best
  /// slot most, so a view keeps much of one keyframe's sensor noise, which the test frame's own
  /// noise does not cancel: on flat surfaces SSIM's structure term pays for both. The keyframes
  /// themselves (keyframes(), the refinement's training targets) stay as captured.
  double keyframe_denoise = 0.0;
  /// Floating textures (slot_alignment.h): YAML keys align_iterations (0 = off; N = N rounds in
  /// every view; or "auto", the default since session 46: one round where a leave-one-out on the
  /// keyframes shows it pays, ChooseAlignment in align_choice.h, chosen again at every
  /// FusionScene::Prepare), align_max_shift_px and align_flow_preset.
  SlotAlignmentOptions align = AutoAlignment();
  static BlendOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const;
};

struct FusionSceneOptions {
  TsdfOptions tsdf;
  BlendOptions blend;
  /// Local submaps. Default (since session 47): a submap per capture, used where a leave-one-out
  /// on the keyframes shows they pay (SubmapOptions::PerCaptureAuto; one capture keeps none).
  SubmapOptions submaps = SubmapOptions::PerCaptureAuto();
  /// Reads {tsdf: {...}, blend: {...}, submaps: {...}} (all optional), then Validate().
  static FusionSceneOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const;
};

/// What to leave out of one rendering (leave-one-out training of the refinement).
struct CandidateRequest {
  /// Keyframe index not to use as a colour source (its frame stays in the TSDF).
  std::optional<int> exclude_keyframe;
  /// Fill ViewCandidates::colours and ::weights (the refinement's per-slot input). A view served
  /// without a refinement needs only the blend: false leaves each slot's two maps empty (k of them
  /// still), which saves allocating, zeroing and writing 16 bytes per slot and pixel.
  bool slot_planes = true;
  /// Overrides the scene's depth source for this view (true: the keyframes', false: the
  /// raycast's); unset = the scene's (BlendOptions::depth, or its auto choice).
  std::optional<bool> keyframe_depth;
  /// Overrides the scene's slot alignment for this view (true: align, with the options' rounds
  /// or one; false: not); unset = the scene's (align_iterations, or its auto choice).
  std::optional<bool> align;
  /// Overrides whether the surface comes from the submaps (true; where the scene has any) or the
  /// global TSDF alone (false); unset = the scene's (SubmapOptions::use, or its auto choice).
  std::optional<bool> submaps;
};

/// Frames arrive at any time (AddFrame); every render uses everything added so far.
/// Thread-compatible (one caller at a time), like TsdfVolume.
class FusionScene {
 public:
  /// `frame_camera`: the calibration of the frames that will be added. Throws
  /// std::invalid_argument on bad options or camera.
  explicit FusionScene(scene::CameraInfo frame_camera, FusionSceneOptions options = {});

  /// Integrates the frame into the TSDF (unless `integrate` is false: a colour source whose
  /// geometry is already fused or must stay out) and keeps it as a keyframe (BlendOptions::
  /// keyframe_min_distance). Returns whether it became a keyframe. Throws std::invalid_argument
  /// naming the frame when its images do not match the frame camera.
  bool AddFrame(const scene::RgbdSample& frame, bool integrate = true);

  /// Integrates the frame into the TSDF (and the current submap, on a second thread at the same
  /// time) without keeping it as a keyframe. A keyframe added next with AddFrame(frame, false)
  /// belongs to that submap.
  void Integrate(const scene::RgbdSample& frame);

  /// Builds the meshes of the global TSDF and of every submap now (TsdfVolume::Prepare), so the
  /// first views do not pay for them, and with BlendOptions::depth "auto" chooses the depth source
  /// from the keyframes added so far (depth_choice()). Optional, except that an auto scene renders
  /// the raycast's depth until its first Prepare.
  void Prepare();

  /// Replaces the submaps with `submaps` (loaded from a saved version) and records the submap of
  /// each keyframe (`keyframe_submaps`, one per keyframe added so far, each -1 or a valid index).
  /// Throws std::invalid_argument when the counts or an index do not fit.
  void RestoreSubmaps(SubmapSet submaps, std::vector<int> keyframe_submaps);

  /// Raycast + keyframe blending at `pose` through `camera` (any size and aspect).
  ViewCandidates RenderCandidates(const scene::Pose& pose, const scene::CameraInfo& camera,
                                  const CandidateRequest& request = {});

  const std::vector<scene::RgbdSample>& keyframes() const { return keyframes_; }
  std::vector<scene::Pose> KeyframePoses() const { return poses_; }
  const scene::CameraInfo& frame_camera() const { return frame_camera_; }
  const FusionSceneOptions& options() const { return options_; }
  TsdfStats Stats() const { return tsdf_.Stats(); }
  TsdfVolume& tsdf() { return tsdf_; }
  /// The submaps (null when SubmapOptions::frames is 0) and the submap of each keyframe (-1: it
  /// was added before any frame was integrated, e.g. from a saved version).
  SubmapSet* submaps() { return submaps_ ? &*submaps_ : nullptr; }
  const std::vector<int>& keyframe_submaps() const { return keyframe_submap_; }
  /// The last BlendOptions::depth "auto" choice (Prepare); default-constructed (raycast, 0
  /// frames) when depth is not auto or before the first Prepare.
  const DepthChoice& depth_choice() const { return depth_choice_; }
  /// The last `align_iterations: auto` choice (Prepare); default-constructed (off, 0 frames) when
  /// the alignment is not auto or before the first Prepare.
  const AlignChoice& align_choice() const { return align_choice_; }
  /// The last `submaps: {use: auto}` choice (Prepare); default-constructed (not used, 0 frames)
  /// when use is not auto or before the first Prepare.
  const SubmapChoice& submap_choice() const { return submap_choice_; }
  /// Whether the views' surface comes from the submaps (the scene has some, and use "always" or
  /// auto chose them).
  bool uses_submaps() const {
    return submaps_ && submaps_->size() > 0 &&
           (options_.submaps.use == "always" || submap_choice_.used);
  }
  /// Whether the views align their slots (align_iterations > 0 and not auto, or auto chose it).
  bool aligned() const {
    return options_.blend.align.iterations > 0 &&
           (!options_.blend.align.automatic || align_choice_.aligned);
  }
  /// What was chosen for the options set to auto, one line for logs ("blocks auto: ...; depth
  /// auto: ...; align auto: ..."; the block size at construction, the others at the last
  /// Prepare), empty when none is auto or nothing was chosen yet.
  std::string AutoChoices() const;
  /// Whether the views carry the keyframes' depth (depth "keyframes", or auto chose it).
  bool keyframe_depth() const {
    return options_.blend.depth == "keyframes" ||
           (options_.blend.depth == "auto" && depth_choice_.source == "keyframes");
  }

 private:
  /// The raycast surface of a view: the global TSDF's, or (submaps) the merged raycast of the
  /// submaps of the slots' keyframes (nearest first), its holes filled from the global TSDF.
  TsdfRaycast Surface(const std::vector<int>& slot_keyframes, const scene::Pose& pose,
                      const scene::CameraInfo& camera, bool use_submaps);

  scene::CameraInfo frame_camera_;
  FusionSceneOptions options_;
  TsdfVolume tsdf_;
  bool blocks_auto_;  ///< TsdfOptions::block_resolution was auto (options_ holds the choice)
  std::optional<SubmapSet> submaps_;
  std::vector<int> keyframe_submap_;
  std::vector<scene::RgbdSample> keyframes_;
  /// The colour each keyframe's slot reads at level 0: its rgb, or the smoothed copy
  /// (BlendOptions::keyframe_denoise).
  std::vector<cv::Mat> blend_rgb_;
  /// Levels 1.. of each keyframe's colour pyramid (BlendOptions::keyframe_levels).
  std::vector<std::vector<cv::Mat>> colour_levels_;
  /// Levels 1.. of each keyframe's depth pyramid (DepthPyramid), read by the visibility test.
  std::vector<std::vector<cv::Mat>> depth_levels_;
  std::vector<scene::Pose> poses_;
  SubmapChoice submap_choice_;
  DepthChoice depth_choice_;
  AlignChoice align_choice_;
};

}  // namespace p2i::fusion
