/// @file fusion_method.cc
/// @brief The `fusion` registry entry with its optional refinement (see fusion_method.h).
#include "refine/fusion_method.h"

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "fusion/fusion_methods.h"
#include "fusion/fusion_synthesizer.h"
#include "fusion/fusion_version_io.h"
#include "model/learned_refiner.h"
#include "model/p2i_synthesizer.h"
#include "refine/leave_one_out.h"
#include "scene/strict_yaml_reader.h"

namespace p2i::refine {
namespace {

bool IsFile(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

/// `path` as the options' author meant it: relative to the folder of `source` when `source` is a
/// file (p2i bench passes its config file), else relative to the working directory (a node
/// parameter).
std::string ResolveNet(const std::string& path, const std::string& source) {
  if (path.empty() || path.front() == '/' || !IsFile(source)) return path;
  const auto slash = source.rfind('/');
  return slash == std::string::npos ? path : source.substr(0, slash + 1) + path;
}

int Integer(const scene::StrictYamlReader& r, const YAML::Node& map, const std::string& key,
            int fallback) {
  const YAML::Node n = map[key];
  if (!n.IsDefined() || n.IsNull()) return fallback;
  const double v = r.Double(n, "refine." + key);
  if (v != std::floor(v) || std::fabs(v) > 1e9) r.Fail(n, "refine." + key + " must be an integer");
  return static_cast<int>(v);
}

/// The refiner of one built method: the named net (or a fresh one), fine-tuned by leave-one-out
/// on `frames` at the method's output camera when finetune_steps > 0.
std::shared_ptr<model::LearnedRefiner> BuildRefiner(const FusionRefineOptions& o,
                                                    const fusion::FusionSceneOptions& scene_options,
                                                    const scene::RgbdDataset& frames,
                                                    const scene::CameraInfo& camera, int threads) {
  const int k = scene_options.blend.k;
  std::shared_ptr<model::LearnedRefiner> refiner =
      o.net.empty() ? model::LearnedRefiner::Fresh(k) : model::LearnedRefiner::Load(o.net, k);
  if (o.finetune_steps <= 0) return refiner;
  LeaveOneOutOptions loo;
  loo.folds = o.folds;
  loo.keyframe_every = o.keyframe_every;
  loo.fusion_scene = scene_options;
  const std::vector<model::RefineSample> samples = MakeLeaveOneOutSamples(frames, camera, loo);
  if (samples.empty()) {
    throw std::invalid_argument(
        "method 'fusion': refine.finetune_steps is " + std::to_string(o.finetune_steps) +
        " but no training frame sees the surface fused from the others (" +
        std::to_string(frames.frames.size()) +
        " frames): give overlapping frames, or set refine.finetune_steps: 0");
  }
  model::RefineTrainOptions train = o.train;
  train.steps = o.finetune_steps;
  train.threads = std::max(1, threads);
  refiner->refiner().Fit(samples, train);
  return refiner;
}

/// The method built from a published version (the trainer node maps online): the version's
/// refinement file when it has one, else `refine.net` as it is (fine-tuning is the mapper's, not
/// repeated at every hot swap).
std::unique_ptr<fusion::FusionSynthesizer> FromVersion(const model::MethodInputs& in,
                                                      const fusion::FusionOptions& options,
                                                      const FusionRefineOptions& refine) {
  fusion::LoadedFusionVersion v =
      fusion::LoadFusionVersion(in.checkpoint_path, options, in.width, in.height);
  const std::string net = !v.refine_path.empty() ? v.refine_path : refine.net;
  if (!net.empty()) v.synthesizer->SetRefiner(model::LearnedRefiner::Load(net, options.scene.blend.k));
  return std::move(v.synthesizer);
}

/// `p2i_fill: PATH`: resolved like refine.net and checked to be a file; "" when absent.
std::string ReadP2iFill(const YAML::Node& options, const std::string& source) {
  const YAML::Node n = options["p2i_fill"];
  if (!n.IsDefined() || n.IsNull()) return "";
  const scene::StrictYamlReader r(source);
  const std::string given = r.String(n, "p2i_fill");
  const std::string path = ResolveNet(given, source);
  if (!IsFile(path)) {
    r.Fail(n, "p2i_fill: no P2I-NET checkpoint '" + path + "'" +
                  (given != path ? " ('" + given + "' relative to " + source + ")" : "") +
                  ": give a `p2i train` checkpoint or `p2i export` file trained on the same frames "
                  "at the view's resolution, or drop the key");
  }
  return path;
}

}  // namespace

FusionRefineOptions FusionRefineOptions::FromYaml(const YAML::Node& node, const std::string& source) {
  const scene::StrictYamlReader r(source);
  r.CheckKeys(node,
              {"net", "finetune_steps", "folds", "keyframe_every", "lr", "batch_size", "crop",
               "ssim_weight", "depth_weight", "seed"},
              "fusion refine options");
  FusionRefineOptions o;
  if (node["net"] && !node["net"].IsNull()) o.net = r.String(node["net"], "refine.net");
  o.finetune_steps = Integer(r, node, "finetune_steps", o.finetune_steps);
  o.folds = Integer(r, node, "folds", o.folds);
  o.keyframe_every = Integer(r, node, "keyframe_every", o.keyframe_every);
  o.train.batch_size = Integer(r, node, "batch_size", o.train.batch_size);
  o.train.crop = Integer(r, node, "crop", o.train.crop);
  const int seed = Integer(r, node, "seed", static_cast<int>(o.train.seed));
  if (seed < 0) r.Fail(node["seed"], "refine.seed must be >= 0, got " + std::to_string(seed));
  o.train.seed = static_cast<uint64_t>(seed);
  r.OptionalDouble(node, "lr", "refine", &o.train.lr);
  r.OptionalDouble(node, "ssim_weight", "refine", &o.train.ssim_weight);
  r.OptionalDouble(node, "depth_weight", "refine", &o.train.depth_weight);
  try {
    o.Validate();
  } catch (const std::invalid_argument& e) {
    r.Fail(node, e.what());
  }
  const std::string given = o.net;
  o.net = ResolveNet(o.net, source);
  if (!o.net.empty() && !IsFile(o.net)) {
    r.Fail(node["net"], "refine.net: no refinement file '" + o.net + "'" +
                            (given != o.net ? " ('" + given + "' relative to " + source + ")" : "") +
                            ": give the path of a `p2i refine train-sim` output such as "
                            "models/refine_sim.pt, or drop the key");
  }
  return o;
}

void FusionRefineOptions::Validate() const {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("FusionRefineOptions: " + what);
  };
  if (finetune_steps < 0) fail("finetune_steps must be >= 0, got " + std::to_string(finetune_steps));
  if (folds < 2) fail("folds must be >= 2, got " + std::to_string(folds));
  if (keyframe_every < 1) fail("keyframe_every must be >= 1, got " + std::to_string(keyframe_every));
  model::RefineTrainOptions t = train;
  t.steps = finetune_steps;
  t.Validate();
}

const std::vector<std::string>& FusionMethodOptionKeys() {
  static const std::vector<std::string> keys = [] {
    std::vector<std::string> k = fusion::FusionOptionKeys();
    k.push_back("refine");
    k.push_back("p2i_fill");
    return k;
  }();
  return keys;
}

model::MethodFactory ConfigureFusionMethod(const YAML::Node& options, const std::string& source) {
  fusion::FusionOptions fusion_options;
  FusionRefineOptions refine;
  std::string p2i_fill;
  if (options.IsDefined() && !options.IsNull()) {
    const std::vector<std::string>& keys = FusionMethodOptionKeys();
    scene::StrictYamlReader(source).CheckKeys(options, {keys.begin(), keys.end()}, "fusion options");
    YAML::Node base = YAML::Clone(options);
    if (options["refine"]) {
      refine = FusionRefineOptions::FromYaml(options["refine"], source);
      base.remove("refine");
    }
    p2i_fill = ReadP2iFill(options, source);
    base.remove("p2i_fill");
    fusion_options = fusion::FusionOptions::FromYaml(base, source);
    fusion_options.Validate();
  }
  return [fusion_options, refine, p2i_fill](const model::MethodInputs& in) -> std::unique_ptr<model::ViewSynthesizer> {
    std::unique_ptr<fusion::FusionSynthesizer> built;
    if (!in.checkpoint_path.empty()) {
      built = FromVersion(in, fusion_options, refine);
    } else {
      const scene::RgbdDataset& frames = model::RequireTrainingFrames(in, "fusion");
      auto synth = std::make_unique<fusion::FusionSynthesizer>(frames, fusion_options);
      if (refine.Enabled()) {
        synth->SetRefiner(BuildRefiner(refine, fusion_options.scene, frames, synth->Camera(), in.threads));
      }
      built = std::move(synth);
    }
    if (!p2i_fill.empty()) {
      model::SynthesizerOptions so;
      so.threads = std::max(1, in.threads);
      std::shared_ptr<model::ViewSynthesizer> g = model::LoadSynthesizer(p2i_fill, so);
      built->SetHoleFiller(std::move(g));
    }
    return built;
  };
}

}  // namespace p2i::refine
