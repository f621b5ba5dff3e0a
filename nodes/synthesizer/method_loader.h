/// @file method_loader.h
/// @brief The synthesizer node's SynthesizerLoader, built from the method registry
/// (model/method_registry.h), and the training data the non-learned methods and the coverage
/// score need.
#pragma once

#include <memory>
#include <string>

#include "nodes/synthesizer/synthesizer_core.h"
#include "scene/rgbd_sample.h"

namespace p2i::nodes {

/// Training data from a spec:
///   ""                  -> empty dataset (no baseline frames, no coverage)
///   "builtin:NAME"      -> scene::RenderBuiltinDataset (the built-in SimScene NAME along the
///                          default arm sweep, sim camera) at width x height
///   any other string    -> a dataset folder opened with scene::OpenDataset (capture, TUM,
///                          7-Scenes), centre-cropped and resized to width x height when both > 0
/// Every `stride`-th frame is kept. With `with_frames` false only poses and the camera are
/// filled (frames have empty images): enough for the coverage score, and cheap.
/// Throws std::runtime_error / std::invalid_argument naming the spec on failure.
scene::RgbdDataset LoadTrainingData(const std::string& spec, int width, int height,
                                    bool with_frames, int stride = 1);

struct LoaderOptions {
  int threads = 2;  ///< torch threads of learned methods (process-wide)
  /// The method's own options as a YAML map ("{k: 4, fill_holes: true}" for warp; keys per
  /// method in model/method_registry.cc); "" = the method's defaults.
  std::string method_options;
  /// Output size of a method built from a model version (MethodInputs::width / height).
  int width = 0;
  int height = 0;
};

/// A loader for `method` (a name or alias of model::Methods()): learned methods load
/// spec.checkpoint_path; the others are built over `training` and ignore the checkpoint, except
/// that methods with MethodInfo::loads_versions (fusion) are built from spec.checkpoint_path (a
/// published version folder) when it is set. The options are read and checked here, at
/// start-up. Throws std::invalid_argument for an unknown method, bad options, or a non-learned
/// method without training frames that cannot load versions either.
/// Whether a ModelVersion of `version_method` (ModelVersion.method: a name or alias, "" =
/// unnamed) is for a synthesizer serving `serving_method` (a canonical name): a P2I-NET trainer
/// and a fusion mapper may publish on one topic.
bool VersionIsFor(const std::string& version_method, const std::string& serving_method);

SynthesizerLoader MakeLoader(const std::string& method, const LoaderOptions& options,
                             std::shared_ptr<const scene::RgbdDataset> training);

}  // namespace p2i::nodes
