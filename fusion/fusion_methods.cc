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

}  // namespace

const std::vector<std::string>& FusionOptionKeys() {
  static const std::vector<std::string> keys{"tsdf", "blend", "submaps", "fill_holes"};
  return keys;
}

model::MethodFactory ConfigureOpen3dTsdf(const YAML::Node& options, const std::string& source) {
  const FusionOptions o = ReadOptions(options, source);
  return [o](const model::MethodInputs& in) -> std::unique_ptr<model::ViewSynthesizer> {
    return std::make_unique<Open3dTsdfSynthesizer>(model::RequireTrainingFrames(in, "open3d_tsdf"), o);
  };
}

}  // namespace p2i::fusion
