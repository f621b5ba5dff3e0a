/// @file method_loader.cc
/// @brief Training data and the method factory of the synthesizer node.
#include "nodes/synthesizer/method_loader.h"

#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "model/method_registry.h"
#include "scene/builtin_dataset.h"
#include "scene/dataset_loader.h"
#include "scene/image_ops.h"

namespace p2i::nodes {

scene::RgbdDataset LoadTrainingData(const std::string& spec, int width, int height,
                                    bool with_frames, int stride) {
  if (stride < 1) throw std::invalid_argument("training data '" + spec + "': stride must be >= 1");
  scene::RgbdDataset out;
  if (spec.empty()) return out;
  if (scene::IsBuiltinSpec(spec)) {
    scene::BuiltinDatasetOptions o;
    o.width = width;
    o.height = height;
    o.stride = stride;
    o.with_frames = with_frames;
    return scene::RenderBuiltinDataset(spec, o);
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

bool VersionIsFor(const std::string& version_method, const std::string& serving_method) {
  if (version_method.empty()) return true;  // an older trainer's versions name no method
  const model::MethodInfo* of = model::FindMethod(version_method);
  return of != nullptr && of->name == serving_method;
}

SynthesizerLoader MakeLoader(const std::string& method, const LoaderOptions& options,
                             std::shared_ptr<const scene::RgbdDataset> training) {
  const model::MethodInfo& info = model::GetMethod(method);
  model::MethodFactory factory;
  try {
    const YAML::Node node =
        options.method_options.empty() ? YAML::Node() : YAML::Load(options.method_options);
    factory = info.configure(node, "synthesizer method_options");
  } catch (const std::runtime_error& e) {  // YAML syntax errors and bad keys
    throw std::invalid_argument(e.what());
  }
  model::MethodInputs inputs;
  inputs.training = std::move(training);
  inputs.threads = options.threads;
  inputs.width = options.width;
  inputs.height = options.height;
  if (!info.learned) {
    const auto& t = inputs.training;
    const bool has_frames = t && !t->frames.empty() && !t->frames.front().rgb.empty();
    if (!has_frames && !info.loads_versions) {
      throw std::invalid_argument("method '" + info.name +
                                  "' needs training frames: set the dataset parameter");
    }
    return [factory, inputs](const ModelSpec& spec) {
      model::MethodInputs in = inputs;
      in.checkpoint_path = spec.checkpoint_path;  // "" = over the training frames
      return factory(in);
    };
  }
  return [factory, inputs](const ModelSpec& spec) {
    if (spec.checkpoint_path.empty()) {
      throw std::invalid_argument("model version " + std::to_string(spec.version) +
                                  " has no checkpoint path");
    }
    model::MethodInputs in = inputs;
    in.checkpoint_path = spec.checkpoint_path;
    return factory(in);
  };
}

}  // namespace p2i::nodes
