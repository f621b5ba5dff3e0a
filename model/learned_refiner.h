/// @file learned_refiner.h
/// @brief The learned refinement of the `fusion` method as a fusion::ViewRefiner: packs a view's
/// candidates (fusion/view_candidates.h PackRefinementInput) and runs the refinement U-Net
/// (model/refiner.h) as a residual on the blend. Also builds leave-one-out training samples
/// from candidates. Torch-free header.
#pragma once

#include <memory>
#include <string>

#include "fusion/view_candidates.h"
#include "model/refiner.h"

namespace p2i::model {

/// Depth is packed as metres * this (so a room's depths sit near [0, 1.5]).
constexpr float kRefineDepthScale = 0.25f;

/// Name of the input layout for k slots ("fusion_pack_v1_k<k>"): a refinement file trained on
/// one layout is refused for another.
std::string RefineLayoutName(int k);

/// The network input of one view: PackRefinementInput planes; base = the blend (0 where no
/// surface) and the raycast depth.
RefineInput MakeRefineInput(const fusion::ViewCandidates& candidates);

/// A leave-one-out sample: candidates rendered without `target` (the caller's job: exclude it
/// from the keyframes, ideally from the TSDF) and the frame itself at the candidates' camera
/// (std::invalid_argument when the sizes differ).
RefineSample MakeRefineSample(const fusion::ViewCandidates& candidates,
                              const scene::RgbdSample& target);

/// Not thread-safe (one caller at a time), like every ViewRefiner.
class LearnedRefiner : public fusion::ViewRefiner {
 public:
  explicit LearnedRefiner(std::unique_ptr<Refiner> refiner);
  /// Loads a refinement file for k slots. Throws std::runtime_error naming the file (missing,
  /// another layout).
  static std::unique_ptr<LearnedRefiner> Load(const std::string& path, int k);
  /// A fresh net for k slots (identity on the blend).
  static std::unique_ptr<LearnedRefiner> Fresh(int k, const RefineNetOptions& net = {});

  std::string Name() const override { return "unet"; }
  scene::RgbdSample Refine(const fusion::ViewCandidates& candidates) override;
  int64_t ParameterCount() const override;
  double FlopsPerView(const scene::CameraInfo& camera) const override;

  Refiner& refiner() { return *refiner_; }

 private:
  std::unique_ptr<Refiner> refiner_;
};

}  // namespace p2i::model
