/// @file synthesizer_options.cc
/// @brief The synthesizer node's parameters -> SynthesizerOptions, and their validation.
#include "nodes/synthesizer/synthesizer_options.h"

#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "model/method_registry.h"
#include "nodes/runtime/option_error.h"
#include "util/yaml_flow.h"

namespace p2i::nodes {

namespace {

/// method_options as the loader takes it, YAML text: a string as given (a launch file's quoted
/// "{k: 4}"), a map or list as flow text (method_options:='{k: 4}' on the command line, which
/// arrives parsed), nothing as "".
std::string MethodOptionsText(const YAML::Node& value) {
  if (!value || value.IsNull()) return "";
  if (value.IsScalar()) return value.as<std::string>();
  return util::YamlFlow(value);
}

}  // namespace

SynthesizerOptions SynthesizerOptions::FromParameters(runtime::Parameters& params) {
  SynthesizerOptions o;  // the defaults, written once in the field initialisers
  o.core.method =
      params.Declare<std::string>("method", o.core.method,
                                  "synthesis method (model/method_registry.h): " +
                                      model::MethodNames());
  o.checkpoint = params.Declare<std::string>(
      "checkpoint", o.checkpoint, "learned methods: start-up checkpoint; '' = wait for model_version");
  o.dataset = params.Declare<std::string>(
      "dataset", o.dataset,
      "training data: frames for nearest/warp/fusion, poses for the coverage score; a dataset "
      "folder, builtin:NAME (default arm sweep rendered at width x height) or '' (coverage 0; "
      "fusion then waits for the trainer's versions on model_version)");
  o.width = params.Declare<int>("width", o.width, "resolution of built-in/resized training data and of views "
                                  "built from a fusion version");
  o.height = params.Declare<int>("height", o.height,
                                 "resolution of built-in/resized training data and of views "
                                 "built from a fusion version");
  o.loader.width = o.width;  // methods built from a model version render at this size
  o.loader.height = o.height;
  o.dataset_stride =
      params.Declare<int>("dataset_stride", o.dataset_stride, "keep every N-th training frame");
  o.loader.threads =
      params.Declare<int>("threads", o.loader.threads, "torch threads (learned methods)");
  o.loader.method_options = MethodOptionsText(params.Declare<YAML::Node>(
      "method_options", YAML::Node(o.loader.method_options),
      "the method's own options as a YAML map, e.g. '{k: 4}' for warp"));
  o.core.max_poses =
      params.Declare<int>("max_poses", o.core.max_poses, "most poses in one RenderRequest");
  o.core.max_batch =
      params.Declare<int>("max_batch", o.core.max_batch, "poses per network batch");
  o.topic_mode = params.Declare<bool>("topic_mode", o.topic_mode,
                                      "render planned_poses onto views (latest-only)");
  return o;
}

void SynthesizerOptions::Validate() const {
  core.Validate();
  using runtime::CheckOption;
  CheckOption(width >= 0, "synthesizer", "width", width, "be >= 0",
              "0 (with height 0) = the dataset's own size");
  CheckOption(height >= 0, "synthesizer", "height", height, "be >= 0",
              "0 (with width 0) = the dataset's own size");
  CheckOption(dataset_stride >= 1, "synthesizer", "dataset_stride", dataset_stride, "be >= 1",
              "1 = every frame of the dataset");
  CheckOption(loader.threads >= 1, "synthesizer", "threads", loader.threads, "be >= 1",
              "e.g. threads:=1");
  runtime::CheckSizePair("synthesizer", width, height,
                         "set both (resize the training data) or neither (the dataset's own size)");
}

bool SynthesizerOptions::Learned() const {
  const model::MethodInfo* method = model::FindMethod(core.method);
  return method != nullptr && method->learned;
}

}  // namespace p2i::nodes
