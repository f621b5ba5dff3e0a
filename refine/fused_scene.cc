/// @file fused_scene.cc
/// @brief MakeFusedScene over the fusion method's own scene (fusion::FusionScene: the one TSDF
/// and keyframe blending of the codebase), created at the first call with that call's camera.
#include "refine/fused_scene.h"

#include <optional>
#include <stdexcept>

#include "fusion/fusion_scene.h"

namespace p2i::refine {

void FusedSceneOptions::Validate() const {
  if (!(voxel_size_m > 0.002 && voxel_size_m < 1.0))
    throw std::invalid_argument("FusedSceneOptions: voxel_size_m must be in (0.002, 1) m, got " +
                                std::to_string(voxel_size_m));
  if (sdf_trunc_m < 0)
    throw std::invalid_argument("FusedSceneOptions: sdf_trunc_m must be >= 0, got " +
                                std::to_string(sdf_trunc_m));
  if (!(depth_max_m > 0))
    throw std::invalid_argument("FusedSceneOptions: depth_max_m must be > 0, got " +
                                std::to_string(depth_max_m));
  if (k < 1 || k > 8)
    throw std::invalid_argument("FusedSceneOptions: k must be in [1, 8], got " + std::to_string(k));
}

namespace {

fusion::FusionSceneOptions ToFusionOptions(const FusedSceneOptions& o) {
  fusion::FusionSceneOptions f;
  f.tsdf.voxel_size_m = o.voxel_size_m;
  if (o.sdf_trunc_m > 0) f.tsdf.trunc_voxels = o.sdf_trunc_m / o.voxel_size_m;
  f.tsdf.depth_max_m = o.depth_max_m;
  f.blend.k = o.k;
  f.Validate();
  return f;
}

FusedSceneOptions FromFusionOptions(const fusion::FusionSceneOptions& f) {
  FusedSceneOptions o;
  o.voxel_size_m = f.tsdf.voxel_size_m;
  o.sdf_trunc_m = f.tsdf.trunc_voxels * f.tsdf.voxel_size_m;
  o.depth_max_m = f.tsdf.depth_max_m;
  o.k = f.blend.k;
  return o;
}

class SceneOverFusion : public FusedScene {
 public:
  explicit SceneOverFusion(const FusedSceneOptions& o) : options_(o), fusion_options_(ToFusionOptions(o)) {}
  explicit SceneOverFusion(const fusion::FusionSceneOptions& f)
      : options_(FromFusionOptions(f)), fusion_options_(f) {}

  void Integrate(const scene::RgbdSample& frame, const scene::CameraInfo& camera) override {
    Scene(camera).Integrate(frame);
  }

  void AddKeyframe(const scene::RgbdSample& frame, const scene::CameraInfo& camera) override {
    Scene(camera).AddFrame(frame, /*integrate=*/false);
  }

  size_t Keyframes() const override { return scene_ ? scene_->keyframes().size() : 0; }

  void Prepare() override {
    if (scene_) scene_->Prepare();
  }

  fusion::ViewCandidates Render(const scene::Pose& pose, const scene::CameraInfo& camera) override {
    return Scene(camera).RenderCandidates(pose, camera);
  }

  void SaveTsdf(const std::string& path) const override {
    if (!scene_) throw std::runtime_error("fused scene: nothing fused yet, no TSDF to save to " + path);
    scene_->tsdf().Save(path);
  }
  const FusedSceneOptions& options() const override { return options_; }

 private:
  /// The scene, created with the first camera seen. Keyframes must all have its size (the blend
  /// projects into them with one calibration: FusionScene::AddFrame says so otherwise); the TSDF
  /// and renders take any camera.
  fusion::FusionScene& Scene(const scene::CameraInfo& camera) {
    if (!scene_) scene_.emplace(camera, fusion_options_);
    return *scene_;
  }

  FusedSceneOptions options_;
  fusion::FusionSceneOptions fusion_options_;
  mutable std::optional<fusion::FusionScene> scene_;
};

}  // namespace

std::unique_ptr<FusedScene> MakeFusedScene(const FusedSceneOptions& options) {
  options.Validate();
  return std::make_unique<SceneOverFusion>(options);
}

std::unique_ptr<FusedScene> MakeFusedScene(const fusion::FusionSceneOptions& options) {
  options.Validate();
  return std::make_unique<SceneOverFusion>(options);
}

}  // namespace p2i::refine
