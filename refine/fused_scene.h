/// @file fused_scene.h
/// @brief The slice of the fusion geometry + appearance the refinement's training needs: fuse
/// frames into a TSDF, keep keyframes, render a view's candidates (fusion/view_candidates.h),
/// save the TSDF. MakeFusedScene builds it over fusion::FusionScene (fused_scene.cc).
#pragma once

#include <memory>
#include <string>

#include "fusion/fusion_scene.h"
#include "fusion/view_candidates.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace p2i::refine {

struct FusedSceneOptions {
  double voxel_size_m = 0.03;
  double sdf_trunc_m = 0.0;   ///< 0 = 4 voxels
  double depth_max_m = 5.0;
  int k = 4;                  ///< keyframe slots per view
  void Validate() const;
};

/// Not thread-safe: one caller at a time.
class FusedScene {
 public:
  virtual ~FusedScene() = default;
  /// Fuses a frame into the TSDF (any size; `camera` is the frame's).
  virtual void Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera) = 0;
  /// Adds a keyframe for appearance (its colours and its own depth for the visibility test).
  virtual void AddKeyframe(const scene::RgbdSample& frame, const scene::CameraInfo& camera) = 0;
  virtual size_t Keyframes() const = 0;
  /// Builds the meshes and makes the options' auto choices (depth source, slot alignment) from
  /// the keyframes added so far, as a served scene does at load (fusion::FusionScene::Prepare),
  /// so that renders after it are those a served view of the same frames gets. Nothing fused yet:
  /// nothing to do.
  virtual void Prepare() = 0;
  /// The candidates of the view at `pose` seen by `camera`.
  virtual fusion::ViewCandidates Render(const scene::Pose& pose, const scene::CameraInfo& camera) = 0;
  /// Writes the TSDF to `path` in full before returning.
  virtual void SaveTsdf(const std::string& path) const = 0;
  virtual const FusedSceneOptions& options() const = 0;
};

/// Over the fusion code (fusion/). Throws std::invalid_argument on bad options.
std::unique_ptr<FusedScene> MakeFusedScene(const FusedSceneOptions& options);
/// The same with the `fusion` method's own full options (every tsdf and blend key as the method
/// was configured): the refinement then trains on the candidates the method will render.
/// options() reports the voxel size, truncation, depth range and k of `options`.
std::unique_ptr<FusedScene> MakeFusedScene(const fusion::FusionSceneOptions& options);

}  // namespace p2i::refine
