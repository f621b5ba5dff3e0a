/// @file leave_one_out.cc
/// @brief Leave-one-out samples by interleaved folds (see leave_one_out.h).
#include "refine/leave_one_out.h"

#include <stdexcept>

#include "model/learned_refiner.h"
#include "scene/image_ops.h"

namespace p2i::refine {

void LeaveOneOutOptions::Validate() const {
  if (folds < 2) throw std::invalid_argument("LeaveOneOutOptions: folds must be >= 2");
  if (keyframe_every < 1) throw std::invalid_argument("LeaveOneOutOptions: keyframe_every must be >= 1");
  if (fusion_scene) {
    fusion_scene->Validate();
  } else {
    scene.Validate();
  }
}

std::unique_ptr<FusedScene> FuseAll(const scene::RgbdDataset& frames,
                                    const FusedSceneOptions& options, int keyframe_every) {
  auto fused = MakeFusedScene(options);
  for (size_t i = 0; i < frames.frames.size(); ++i) {
    fused->Integrate(frames.frames[i], frames.camera);
    if (i % static_cast<size_t>(keyframe_every) == 0)
      fused->AddKeyframe(frames.frames[i], frames.camera);
  }
  fused->Prepare();
  return fused;
}

std::vector<model::RefineSample> MakeLeaveOneOutSamples(const scene::RgbdDataset& frames,
                                                        const scene::CameraInfo& render_camera,
                                                        const LeaveOneOutOptions& options) {
  options.Validate();
  const size_t n = frames.frames.size();
  const size_t folds = static_cast<size_t>(options.folds);
  std::vector<model::RefineSample> out;
  if (n < 2) return out;
  for (size_t f = 0; f < folds && f < n; ++f) {
    auto fused = options.fusion_scene ? MakeFusedScene(*options.fusion_scene)
                                      : MakeFusedScene(options.scene);
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i) {
      if (i % folds == f) continue;
      fused->Integrate(frames.frames[i], frames.camera);
      if (kept++ % static_cast<size_t>(options.keyframe_every) == 0)
        fused->AddKeyframe(frames.frames[i], frames.camera);
    }
    // The auto choices of this fold's keyframes, as the served scene makes them from all of its
    // own: the refinement trains on the candidates it will be given.
    fused->Prepare();
    for (size_t i = f; i < n; i += folds) {
      const fusion::ViewCandidates c = fused->Render(frames.frames[i].pose, render_camera);
      if (c.coverage.observed_fraction <= 0.0) continue;
      const scene::RgbdSample target = scene::CenterCropResizeSample(
          frames.frames[i], render_camera.image_width, render_camera.image_height);
      out.push_back(model::MakeRefineSample(c, target));
    }
  }
  return out;
}

}  // namespace p2i::refine
