/// @file learned_refiner.cc
/// @brief LearnedRefiner and the candidate -> network input packing (see learned_refiner.h).
#include "model/learned_refiner.h"

#include <stdexcept>

namespace p2i::model {

std::string RefineLayoutName(int k) { return "fusion_pack_v1_k" + std::to_string(k); }

RefineInput MakeRefineInput(const fusion::ViewCandidates& c) {
  RefineInput in;
  fusion::PackRefinementInput(c, &in.planes, kRefineDepthScale);
  in.channels = fusion::RefinementChannels(c.k());
  in.base_rgb = c.blended;
  in.base_depth = c.depth;
  return in;
}

RefineSample MakeRefineSample(const fusion::ViewCandidates& c, const scene::RgbdSample& target) {
  if (target.rgb.size() != c.depth.size() || target.depth.size() != c.depth.size())
    throw std::invalid_argument("leave-one-out sample " + target.id + ": frame is " +
                                std::to_string(target.rgb.cols) + "x" +
                                std::to_string(target.rgb.rows) + ", candidates are " +
                                std::to_string(c.depth.cols) + "x" + std::to_string(c.depth.rows));
  RefineSample s;
  s.input = MakeRefineInput(c);
  s.target_rgb = target.rgb;
  s.target_depth = target.depth;
  return s;
}

LearnedRefiner::LearnedRefiner(std::unique_ptr<Refiner> refiner) : refiner_(std::move(refiner)) {
  if (!refiner_) throw std::invalid_argument("LearnedRefiner: no refiner");
}

std::unique_ptr<LearnedRefiner> LearnedRefiner::Load(const std::string& path, int k) {
  return std::make_unique<LearnedRefiner>(Refiner::Load(path, RefineLayoutName(k)));
}

std::unique_ptr<LearnedRefiner> LearnedRefiner::Fresh(int k, const RefineNetOptions& net) {
  RefineNetOptions o = net;
  o.in_channels = fusion::RefinementChannels(k);
  return std::make_unique<LearnedRefiner>(std::make_unique<Refiner>(o, RefineLayoutName(k)));
}

scene::RgbdSample LearnedRefiner::Refine(const fusion::ViewCandidates& c) {
  scene::RgbdSample out;
  out.pose = c.pose;
  refiner_->Refine(MakeRefineInput(c), &out.rgb, &out.depth);
  return out;
}

int64_t LearnedRefiner::ParameterCount() const { return refiner_->ParameterCount(); }

double LearnedRefiner::FlopsPerView(const scene::CameraInfo& camera) const {
  return 2.0 * refiner_->MacsPerPixel() * camera.image_width * camera.image_height;
}

}  // namespace p2i::model
