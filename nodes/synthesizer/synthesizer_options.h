/// @file synthesizer_options.h
/// @brief Every parameter of the synthesizer node in one Options struct: defaults in the field
/// initialisers (written once), read from the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/runtime/parameters.h"
#include "nodes/synthesizer/method_loader.h"
#include "nodes/synthesizer/synthesizer_core.h"

namespace p2i::nodes {

/// The synthesizer node's configuration (docs/SYNTHESIZER.md lists the parameters). A value
/// type: thread-compatible.
struct SynthesizerOptions {
  SynthesizerCoreOptions core;  ///< method, max_poses, max_batch
  LoaderOptions loader;         ///< threads, method_options
  /// Learned methods: the start-up checkpoint; "" = wait for a model_version.
  std::string checkpoint;
  /// Training data: frames for nearest/warp, poses for the coverage score (LoadTrainingData).
  std::string dataset = "builtin:small_office";
  int width = 64;   ///< resolution of built-in / resized training data
  int height = 64;
  int dataset_stride = 1;  ///< keep every N-th training frame
  bool topic_mode = true;  ///< render planned_poses onto views (latest-only)

  /// Declares every parameter (name, type, the default of a default-constructed struct,
  /// description: what --help shows) and returns the values supplied or the defaults. Throws
  /// runtime::StartupError for a value of the wrong type.
  static SynthesizerOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter and its bad value.
  void Validate() const;

  /// Whether core.method is a learned method of model/method_registry.h (false if unknown).
  bool Learned() const;
};

}  // namespace p2i::nodes
