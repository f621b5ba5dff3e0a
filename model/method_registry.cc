/// @file method_registry.cc
/// @brief The table of synthesis methods (model/method_registry.h says how to add one).
#include "model/method_registry.h"

#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "fusion/fusion_methods.h"
#include "model/baseline_nearest.h"
#include "model/baseline_warp.h"
#include "model/p2i_synthesizer.h"
#include "refine/fusion_method.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::model {
namespace {

/// An options map that is null or empty means "defaults".
bool NoOptions(const YAML::Node& node) { return !node.IsDefined() || node.IsNull(); }

/// p2i and cnn: a checkpoint of model::Trainer; LoadSynthesizer reads which network it holds.
MethodFactory ConfigureLearned(const YAML::Node& options, const std::string& source) {
  if (!NoOptions(options) && options.size() > 0) {
    scene::StrictYamlReader(source).CheckKeys(options, {}, "the options of a learned method");
  }
  return [](const MethodInputs& in) -> std::unique_ptr<ViewSynthesizer> {
    if (in.checkpoint_path.empty()) {
      throw std::invalid_argument("a learned method needs a checkpoint path");
    }
    SynthesizerOptions so;
    so.threads = in.threads;
    so.Validate();
    return LoadSynthesizer(in.checkpoint_path, so);
  };
}

MethodFactory ConfigureNearest(const YAML::Node& options, const std::string& source) {
  const NearestKeyframeOptions o = NoOptions(options)
                                       ? NearestKeyframeOptions{}
                                       : NearestKeyframeOptions::FromYaml(options, source);
  return [o](const MethodInputs& in) -> std::unique_ptr<ViewSynthesizer> {
    return std::make_unique<NearestKeyframe>(RequireTrainingFrames(in, "nearest"), o);
  };
}

/// The warp method fills holes unless its options say `fill_holes: false` (DepthWarpOptions'
/// own default is off: the class keeps holes visible for its tests and the hole fraction).
MethodFactory ConfigureWarp(const YAML::Node& options, const std::string& source) {
  DepthWarpOptions o;
  if (!NoOptions(options)) o = DepthWarpOptions::FromYaml(options, source);
  if (NoOptions(options) || !options["fill_holes"]) o.fill_holes = true;
  return [o](const MethodInputs& in) -> std::unique_ptr<ViewSynthesizer> {
    return std::make_unique<DepthWarp>(RequireTrainingFrames(in, "warp"), o);
  };
}

/// The table. Fields: name, aliases, summary, learned, default preset, trainer model, option
/// keys, configure.
std::vector<MethodInfo> MakeTable() {
  std::vector<MethodInfo> t;
  t.push_back({"p2i", {"p2i_net"}, "P2I-NET (Kang et al. 2023): conditional GAN, pose -> RGB-D",
               true, "default", "p2i_net", {}, ConfigureLearned});
  t.push_back({"cnn", {"cnn_baseline"}, "the paper's CNN baseline (no discriminator, no ENET)",
               true, "cnn_baseline", "cnn_baseline", {}, ConfigureLearned});
  t.push_back({"nearest", {}, "nearest keyframe: the training frame closest in pose", false, "",
               "", {"metres_per_degree"}, ConfigureNearest});
  t.push_back({"warp", {}, "depth warp (DIBR) of the k nearest training frames", false, "", "",
               {"k", "metres_per_degree", "z_tolerance", "fill_holes"}, ConfigureWarp});
  t.push_back({"fusion", {}, "TSDF geometry (raycast) coloured by view-dependent blending of the k "
               "best visible keyframes (fusion/), optionally refined by a learned U-Net (refine/)",
               false, "", "", refine::FusionMethodOptionKeys(), refine::ConfigureFusionMethod,
               /*loads_versions=*/true});
  t.push_back({"open3d_tsdf", {}, "Open3D's own voxel-colour raycast of the same TSDF (fusion/)",
               false, "", "", fusion::FusionOptionKeys(), fusion::ConfigureOpen3dTsdf});
  return t;
}

}  // namespace

const std::vector<MethodInfo>& Methods() {
  static const std::vector<MethodInfo> table = MakeTable();
  return table;
}

const MethodInfo* FindMethod(const std::string& name) {
  for (const MethodInfo& m : Methods()) {
    if (m.name == name) return &m;
    for (const std::string& a : m.aliases)
      if (a == name) return &m;
  }
  return nullptr;
}

const MethodInfo& GetMethod(const std::string& name) {
  const MethodInfo* m = FindMethod(name);
  if (m == nullptr) {
    throw std::invalid_argument("method '" + name + "' is not one of " + MethodNames());
  }
  return *m;
}

std::string MethodNames() {
  std::string out;
  for (const MethodInfo& m : Methods()) out += (out.empty() ? "" : ", ") + m.name;
  return out;
}

}  // namespace p2i::model
