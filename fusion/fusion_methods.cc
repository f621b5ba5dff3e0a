/// @file fusion_methods.cc
/// @brief `fusion` and `open3d_tsdf` as registry entries.
#include "fusion/fusion_methods.h"

#include <memory>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "fusion/fusion_synthesizer.h"

namespace p2i::fusion {
namespace {

FusionOptions ReadOptions(const YAML::Node& options, const std::string& source) {
  if (!options.IsDefined() || options.IsNull()) return {};
  FusionOptions o = FusionOptions::FromYaml(options, source);
  o.Validate();
  return o;
}

const scene::RgbdDataset& Frames(const model::MethodInputs& in, const char* method) {
  if (!in.training || in.training->frames.empty() || in.training->frames.front().rgb.empty()) {
    throw std::invalid_argument(std::string("method '") + method +
                                "' needs training frames (rgb and depth): give it a dataset");
  }
  return *in.training;
}

}  // namespace

const std::vector<std::string>& FusionOptionKeys() {
  static const std::vector<std::string> keys{"tsdf", "blend", "fill_holes"};
  return keys;
}

model::MethodFactory ConfigureOpen3dTsdf(const YAML::Node& options, const std::string& source) {
  const FusionOptions o = ReadOptions(options, source);
  return [o](const model::MethodInputs& in) -> std::unique_ptr<model::ViewSynthesizer> {
    return std::make_unique<Open3dTsdfSynthesizer>(Frames(in, "open3d_tsdf"), o);
  };
}

}  // namespace p2i::fusion
