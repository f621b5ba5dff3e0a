/// @file method_registry.h
/// @brief The synthesis methods p2i knows, in one table: for each name, how it is configured,
/// how it is trained and how it is loaded as a ViewSynthesizer. `p2i bench` (eval/) and the
/// synthesizer node (nodes/synthesizer/method_loader.cc) both build methods from here, so the
/// list of valid names exists once. Torch-free header.
///
/// Adding a method: write its ViewSynthesizer (model/ or a folder of its own), then add one
/// entry to the table in model/method_registry.cc (name, summary, learned or not, its option
/// keys and a Configure function). Nothing else lists method names. Built as p2i_methods (not
/// p2i_model: the table also lists methods of libraries above p2i_model, e.g. p2i_fusion).
#pragma once

#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/view_synthesizer.h"
#include "scene/rgbd_sample.h"

namespace YAML {
class Node;
}  // namespace YAML

namespace p2i::model {

/// What a configured method is built from.
struct MethodInputs {
  /// The training frames of the scene (rgb, depth, poses, camera). Methods that are not learned
  /// build from them; every method's coverage score uses their poses. May be null for learned
  /// methods.
  std::shared_ptr<const scene::RgbdDataset> training;
  /// Learned methods: the checkpoint to load (written by model::Trainer or `p2i export`).
  /// Methods with MethodInfo::loads_versions: a published model version folder to build from
  /// instead of `training` ("" = build over `training`).
  std::string checkpoint_path;
  /// Output size of a method built from a model version (the version's frames are
  /// centre-cropped and resized to it); 0 x 0 = the version's own frame size.
  int width = 0;
  int height = 0;
  int threads = 1;  ///< LibTorch threads of learned methods (process-wide)
};

/// Builds one synthesizer. Throws std::invalid_argument (missing frames or checkpoint) or
/// std::runtime_error (unreadable checkpoint) naming what is wrong.
using MethodFactory = std::function<std::unique_ptr<ViewSynthesizer>(const MethodInputs&)>;

/// One synthesis method.
struct MethodInfo {
  std::string name;                  ///< the canonical name: "p2i", "cnn", "nearest", "warp", "fusion"
  std::vector<std::string> aliases;  ///< other spellings accepted in configs ("p2i_net")
  std::string summary;               ///< one line, for help texts and docs
  /// Learned methods are trained by model::Trainer from a P2iConfig preset (`default_preset`
  /// unless the config names one) and loaded from its checkpoint. The others have no training
  /// step: they are built from the training frames.
  bool learned = false;
  std::string default_preset;  ///< learned: a model/presets/ name
  /// learned: the network the trainer builds (P2iConfig::model: "p2i_net", "cnn_baseline"),
  /// forced over the preset's so that the method name decides it.
  std::string trainer_model;
  /// Keys of the method's own options (bench config method entries, the synthesizer's
  /// `method_options` map); everything else in those places is common to all methods.
  std::vector<std::string> option_keys;
  /// Reads the method's options from a YAML map (null or empty: the defaults) and validates
  /// them once, at start-up; returns the factory. Bad keys or values throw std::runtime_error
  /// naming `source`, the line and the key.
  std::function<MethodFactory(const YAML::Node& options, const std::string& source)> configure;
  /// Not learned, but also built from a published model version (MethodInputs::checkpoint_path:
  /// a folder the trainer node writes while it maps, e.g. fusion's TSDF snapshots), so the
  /// synthesizer hot-swaps its versions like a learned method's checkpoints.
  bool loads_versions = false;
};

/// The training frames of `in`, or std::invalid_argument "method 'NAME' needs training frames
/// ..." when there are none (or they have no images). Inline: the method libraries below
/// p2i_methods (p2i_fusion, p2i_refine) call it too.
inline const scene::RgbdDataset& RequireTrainingFrames(const MethodInputs& in, const std::string& method) {
  if (!in.training || in.training->frames.empty() || in.training->frames.front().rgb.empty()) {
    throw std::invalid_argument("method '" + method +
                                "' needs training frames (rgb and depth): give it a dataset");
  }
  return *in.training;
}

/// Every method, in table order (the order of help texts and error messages).
const std::vector<MethodInfo>& Methods();
/// The method called `name` (canonical name or alias), or null.
const MethodInfo* FindMethod(const std::string& name);
/// As FindMethod; throws std::invalid_argument "method 'x' is not one of p2i, cnn, ..." instead
/// of returning null.
const MethodInfo& GetMethod(const std::string& name);
/// "p2i, cnn, nearest, warp": the canonical names for messages.
std::string MethodNames();

}  // namespace p2i::model
