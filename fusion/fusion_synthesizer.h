/// @file fusion_synthesizer.h
/// @brief The `fusion` method (issue 12): TSDF geometry + view-dependent keyframe blending
/// (FusionScene), optionally refined by a ViewRefiner, behind model::ViewSynthesizer; and the
/// `open3d_tsdf` peer (Open3D's own voxel-colour rendering of the same TSDF).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "fusion/fusion_scene.h"
#include "fusion/view_candidates.h"
#include "model/view_synthesizer.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::fusion {

struct FusionOptions {
  FusionSceneOptions scene;
  /// Fill the pixels the TSDF never observed (no raycast hit) by push-pull, RGB and depth, as
  /// depth warp's fill_holes does. Off: they stay rgb (0, 0, 0), depth 0.
  bool fill_holes = true;
  /// Reads {tsdf: {...}, blend: {...}, fill_holes: bool} (all optional), then Validate().
  /// Unknown keys and bad values throw std::runtime_error naming `source`, the line and the key.
  static FusionOptions FromYaml(const YAML::Node& node, const std::string& source);
  void Validate() const { scene.Validate(); }
};

/// The view served from a surface's maps: 8-bit RGB of `rgb` (CV_32FC3 in [0, 1]), a copy of
/// `depth`, and the pixels without a surface (depth 0) push-pull filled, RGB and depth, when
/// `fill` (FusionOptions::fill_holes), except the RGB of the pixels set in `far` (CV_8UC1, may be
/// empty: ViewCandidates::far), which already hold a far-field colour. The `fusion` and
/// `open3d_tsdf` views, and `p2i refine eval`'s blend, are made here.
scene::RgbdSample ToView(const scene::Pose& pose, const cv::Mat& rgb, const cv::Mat& depth, bool fill,
                         const std::string& id, const cv::Mat& far = cv::Mat());

/// `fusion`. Built from training frames (all integrated and kept as keyframes) and fed more at
/// any time with AddFrame. Render: RenderCandidates at the pose and the output camera, then the
/// refiner when there is one, else the blend (8-bit) with the raycast depth; the hole filler's
/// view where the TSDF saw nothing (when one is set), then the remaining holes filled when
/// fill_holes. Not thread-safe (ViewSynthesizer contract).
class FusionSynthesizer : public model::ViewSynthesizer {
 public:
  /// `training` may have no frames (an online scene starts empty: views are all holes until
  /// frames arrive). Output at `output_camera`, default the training camera. Throws
  /// std::invalid_argument on bad options, a bad camera or a frame of the wrong size.
  FusionSynthesizer(const scene::RgbdDataset& training, FusionOptions options = {},
                    std::optional<scene::CameraInfo> output_camera = std::nullopt,
                    std::shared_ptr<ViewRefiner> refiner = nullptr);

  std::string Name() const override { return "fusion"; }
  scene::CameraInfo Camera() const override { return output_camera_; }
  scene::RgbdSample Render(const scene::Pose& pose) override;
  std::vector<scene::RgbdSample> RenderBatch(const std::vector<scene::Pose>& poses) override;
  std::vector<model::ViewGeometry> LastGeometry() const override { return last_geometry_; }
  int64_t ParameterCount() const override { return refiner_ ? refiner_->ParameterCount() : 0; }
  double FlopsPerView() const override { return refiner_ ? refiner_->FlopsPerView(output_camera_) : 0.0; }

  /// Integrates a new frame (training camera) and keeps it as a keyframe.
  bool AddFrame(const scene::RgbdSample& frame) { return scene_.AddFrame(frame); }
  /// The candidates of one view at any camera (the refinement's input).
  ViewCandidates RenderCandidates(const scene::Pose& pose, const scene::CameraInfo& camera,
                                  const CandidateRequest& request = {}) {
    return scene_.RenderCandidates(pose, camera, request);
  }
  /// Render at another camera than Camera() (any size and aspect).
  scene::RgbdSample RenderAt(const scene::Pose& pose, const scene::CameraInfo& camera);

  void SetRefiner(std::shared_ptr<ViewRefiner> refiner) { refiner_ = std::move(refiner); }
  /// The pixels the TSDF never observed (no raycast hit) take `filler`'s view at the same pose
  /// (issue 12 point 3: P2I-NET's G where geometry never saw the surface), RGB and depth; after
  /// it, fill_holes' push-pull fills only what is still invalid (the filler's depth of 0). Its
  /// Camera() must be the view's (size and intrinsics): a view at another camera throws
  /// std::invalid_argument. nullptr = off (the default).
  void SetHoleFiller(std::shared_ptr<model::ViewSynthesizer> filler) { filler_ = std::move(filler); }
  /// Pixels of the last view that the hole filler coloured / all pixels (0 without a filler).
  double LastFillerFraction() const { return last_filler_fraction_; }
  FusionScene& scene() { return scene_; }
  /// Coverage of the last rendered view; fraction of its pixels the TSDF never observed.
  const ViewCoverage& LastCoverage() const { return last_coverage_; }
  double LastHoleFraction() const { return 1.0 - last_coverage_.observed_fraction; }

 private:
  FusionOptions options_;
  FusionScene scene_;
  scene::CameraInfo output_camera_;
  std::shared_ptr<ViewRefiner> refiner_;
  std::shared_ptr<model::ViewSynthesizer> filler_;
  double last_filler_fraction_ = 0.0;
  ViewCoverage last_coverage_;
  std::vector<model::ViewGeometry> last_geometry_;  ///< of the last Render / RenderBatch
};

/// `open3d_tsdf`: what a user of Open3D would pick: the same TSDF, rendered by its own raycast of
/// depth and interpolated voxel colour (no keyframes; TsdfOptions::surface is always "raycast"
/// here, with the hit refinement and crack fill as configured). Holes filled like fusion's.
class Open3dTsdfSynthesizer : public model::ViewSynthesizer {
 public:
  Open3dTsdfSynthesizer(const scene::RgbdDataset& training, FusionOptions options = {},
                        std::optional<scene::CameraInfo> output_camera = std::nullopt);

  std::string Name() const override { return "open3d_tsdf"; }
  scene::CameraInfo Camera() const override { return output_camera_; }
  scene::RgbdSample Render(const scene::Pose& pose) override;
  void AddFrame(const scene::RgbdSample& frame) { tsdf_.Integrate(frame, frame_camera_); }
  double LastHoleFraction() const { return last_hole_fraction_; }
  TsdfStats Stats() const { return tsdf_.Stats(); }

 private:
  FusionOptions options_;
  TsdfVolume tsdf_;
  scene::CameraInfo frame_camera_;
  scene::CameraInfo output_camera_;
  double last_hole_fraction_ = 0.0;
};

}  // namespace p2i::fusion
