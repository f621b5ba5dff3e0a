/// @file cross_scene.cc
/// @brief TrainCrossScene (see cross_scene.h).
#include "refine/cross_scene.h"

#include <chrono>
#include <stdexcept>

#include "fusion/view_candidates.h"
#include "model/learned_refiner.h"

namespace p2i::refine {

void CrossSceneOptions::Validate() const {
  scenes.Validate();
  if (held_out_scenes < 0 || held_out_scenes >= scenes.scenes)
    throw std::invalid_argument("CrossSceneOptions: held_out_scenes must be in [0, scenes)");
  loo.Validate();
  fit.Validate();
}

CrossSceneReport TrainCrossScene(const CrossSceneOptions& options, const std::string& out_path) {
  options.Validate();
  using Clock = std::chrono::steady_clock;
  CrossSceneReport report;
  const auto t0 = Clock::now();
  const std::vector<SimTrainingScene> scenes = MakeSimScenes(options.scenes);
  std::vector<model::RefineSample> train, val;
  std::string names;
  for (size_t i = 0; i < scenes.size(); ++i) {
    const bool held = static_cast<int>(i) >= options.scenes.scenes - options.held_out_scenes;
    auto samples = MakeLeaveOneOutSamples(scenes[i].frames, scenes[i].frames.camera, options.loo);
    auto& dst = held ? val : train;
    for (auto& s : samples) dst.push_back(std::move(s));
    if (!held) names += (names.empty() ? "" : ", ") + scenes[i].name;
  }
  report.train_samples = static_cast<int>(train.size());
  report.val_samples = static_cast<int>(val.size());
  if (train.empty()) throw std::runtime_error("TrainCrossScene: no training samples");
  const auto t1 = Clock::now();
  report.seconds_samples = std::chrono::duration<double>(t1 - t0).count();
  model::RefineNetOptions net = options.net;
  net.in_channels = fusion::RefinementChannels(options.loo.scene.k);
  model::Refiner refiner(net, model::RefineLayoutName(options.loo.scene.k));
  report.parameters = refiner.ParameterCount();
  report.fit = refiner.Fit(train, options.fit);
  report.seconds_fit = std::chrono::duration<double>(Clock::now() - t1).count();
  if (!val.empty()) report.val = refiner.Evaluate(val);
  refiner.Save(out_path, "sim scenes (leave-one-out): " + names);
  return report;
}

}  // namespace p2i::refine
