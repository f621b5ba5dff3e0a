/// @file leave_one_out.h
/// @brief Leave-one-out training samples for the refinement: frame i rendered from the other
/// frames' geometry and colours, paired with frame i.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "model/refiner.h"
#include "refine/fused_scene.h"
#include "scene/rgbd_sample.h"

namespace p2i::refine {

struct LeaveOneOutOptions {
  /// Frames are split into `folds` interleaved folds (frame i in fold i % folds); the frames of
  /// fold f are rendered from a scene fused from all other folds (TSDF and keyframes), so frame
  /// i never sees itself. folds = n would be exact leave-one-out at n times the fusing cost; the
  /// default 4 also hides 1/4 of the neighbours (a slightly harder task than at test time).
  int folds = 4;
  /// Keyframes: every `keyframe_every`-th frame of the other folds (1 = all of them).
  int keyframe_every = 1;
  FusedSceneOptions scene;
  /// Set: the folds are fused with these full options of the `fusion` method instead of `scene`
  /// (refine/fusion_method.cc: a method fine-tunes on the candidates it renders).
  std::optional<fusion::FusionSceneOptions> fusion_scene;
  void Validate() const;
  /// The k of the layout the samples have (fusion_scene's blend k when set, else scene.k).
  int K() const { return fusion_scene ? fusion_scene->blend.k : scene.k; }
};

/// Samples at `render_camera` (frames are centre-cropped/resized to it as targets; fusion uses
/// the frames as given). Frames whose view sees no fused surface at all are skipped. Each fold's
/// scene is prepared (FusedScene::Prepare) before its renders: with the fusion defaults' auto
/// depth and alignment, a fold renders with the choices its own keyframes make, as a served scene
/// does with all of them.
std::vector<model::RefineSample> MakeLeaveOneOutSamples(const scene::RgbdDataset& frames,
                                                        const scene::CameraInfo& render_camera,
                                                        const LeaveOneOutOptions& options);

/// A scene fused from every frame (TSDF) with every `keyframe_every`-th frame as a keyframe,
/// prepared (FusedScene::Prepare).
std::unique_ptr<FusedScene> FuseAll(const scene::RgbdDataset& frames,
                                    const FusedSceneOptions& options, int keyframe_every = 1);

}  // namespace p2i::refine
