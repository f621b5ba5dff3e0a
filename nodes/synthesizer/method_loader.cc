/// @file method_loader.cc
/// @brief Training data and the method factory of the synthesizer node.
#include "nodes/synthesizer/method_loader.h"

#include <stdexcept>

#include "model/baseline_nearest.h"
#include "model/baseline_warp.h"
#include "model/p2i_synthesizer.h"
#include "scene/dataset_loader.h"
#include "scene/image_ops.h"
#include "scene/sim_scene.h"
#include "scene/trajectory.h"

namespace p2i::nodes {

scene::CameraInfo BuiltinCamera(int width, int height) {
  return scene::SimScene::DefaultCamera(width, height);
}

scene::RgbdDataset LoadTrainingData(const std::string& spec, int width, int height,
                                    bool with_frames, int stride) {
  if (stride < 1) throw std::invalid_argument("training data '" + spec + "': stride must be >= 1");
  scene::RgbdDataset out;
  if (spec.empty()) return out;
  const std::string kBuiltin = "builtin:";
  if (spec.rfind(kBuiltin, 0) == 0) {
    if (width <= 0 || height <= 0) {
      throw std::invalid_argument("training data '" + spec +
                                  "': width and height must be > 0 for built-in scenes");
    }
    const scene::SimScene sim = scene::SimScene::BuiltIn(spec.substr(kBuiltin.size()));
    out.camera = BuiltinCamera(width, height);
    const std::vector<scene::StampedPose> sweep = scene::GenerateArmSweep({});
    for (size_t i = 0; i < sweep.size(); i += stride) {
      scene::RgbdSample s;
      if (with_frames) {
        s = sim.Render(sweep[i].pose, out.camera, sweep[i].stamp);
      }
      s.stamp = sweep[i].stamp;
      s.pose = sweep[i].pose;
      s.id = "sweep/" + std::to_string(i);
      out.frames.push_back(std::move(s));
    }
    return out;
  }
  const scene::DatasetIndex index = scene::OpenDataset(spec);
  if (index.empty()) throw std::runtime_error("training data '" + spec + "' has no frames");
  out.camera = index.camera();
  for (size_t i = 0; i < index.size(); i += stride) {
    if (with_frames) {
      out.frames.push_back(index.Load(i));
    } else {
      scene::RgbdSample s;
      s.stamp = index.frames()[i].stamp;
      s.pose = index.frames()[i].pose;
      s.id = index.frames()[i].id;
      out.frames.push_back(std::move(s));
    }
  }
  if (width > 0 && height > 0 &&
      (width != out.camera.image_width || height != out.camera.image_height)) {
    if (with_frames) {
      out = scene::CenterCropResizeDataset(out, width, height);
    } else {
      out.camera = scene::CenterCropResizeCamera(out.camera, width, height);
    }
  }
  return out;
}

SynthesizerLoader MakeLoader(const std::string& method, const LoaderOptions& options,
                             std::shared_ptr<const scene::RgbdDataset> training) {
  if (method == "p2i" || method == "cnn") {
    model::SynthesizerOptions so;
    so.threads = options.threads;
    so.Validate();
    return [so](const ModelSpec& spec) -> std::unique_ptr<model::ViewSynthesizer> {
      if (spec.checkpoint_path.empty()) {
        throw std::invalid_argument("model version " + std::to_string(spec.version) +
                                    " has no checkpoint path");
      }
      return model::LoadSynthesizer(spec.checkpoint_path, so);
    };
  }
  if (method == "nearest" || method == "warp") {
    if (!training || training->frames.empty() || training->frames.front().rgb.empty()) {
      throw std::invalid_argument("method '" + method +
                                  "' needs training frames: set the dataset parameter");
    }
    if (method == "nearest") {
      return [training](const ModelSpec&) -> std::unique_ptr<model::ViewSynthesizer> {
        return std::make_unique<model::NearestKeyframe>(*training);
      };
    }
    model::DepthWarpOptions wo;
    wo.k = options.warp_k;
    wo.fill_holes = options.warp_fill_holes;
    wo.Validate();
    return [training, wo](const ModelSpec&) -> std::unique_ptr<model::ViewSynthesizer> {
      return std::make_unique<model::DepthWarp>(*training, wo);
    };
  }
  throw std::invalid_argument("method '" + method + "' is not one of p2i, cnn, nearest, warp");
}

}  // namespace p2i::nodes
