/// @file synthesizer_node.cc
/// @brief SynthesizerNode: parameters, endpoints, wiring to SynthesizerCore.
#include "nodes/synthesizer/synthesizer_node.h"

#include <stdexcept>

#include "model/coverage.h"
#include "model/method_registry.h"
#include "nodes/synthesizer/method_loader.h"
#include "nodes/synthesizer/synthesizer_options.h"

namespace p2i::nodes {

SynthesizerNode::SynthesizerNode(const runtime::NodeArgs& args)
    : runtime::Node("synthesizer", args) {
  SynthesizerOptions options = SynthesizerOptions::FromParameters(Params());
  try {
    options.Validate();
  } catch (const std::invalid_argument& e) {
    throw runtime::StartupError(e.what());
  }
  ParametersDone();  // unknown parameters / --help stop here, before any data is loaded
  StartCore(&options);
  ServeRender();
  if (options.topic_mode) StartTopicMode();
  if (versioned_) SubscribeModelVersions();
  StartStatusTimer();
}

void SynthesizerNode::StartCore(SynthesizerOptions* options) {
  SynthesizerCoreOptions& core_options = options->core;
  const std::string& checkpoint = options->checkpoint;
  const std::string& dataset = options->dataset;
  std::shared_ptr<const model::CoverageScorer> coverage;
  SynthesizerLoader loader;
  try {
    const model::MethodInfo& method = model::GetMethod(core_options.method);
    core_options.method = method.name;  // an alias ("p2i_net") serves under the canonical name
    learned_ = method.learned;
    versioned_ = method.learned || method.loads_versions;
    auto training = std::make_shared<const scene::RgbdDataset>(
        LoadTrainingData(dataset, options->width, options->height, /*with_frames=*/!learned_,
                         options->dataset_stride));
    if (!training->frames.empty()) {
      std::vector<scene::Pose> poses;
      poses.reserve(training->frames.size());
      for (const auto& f : training->frames) poses.push_back(f.pose);
      coverage = std::make_shared<const model::CoverageScorer>(std::move(poses));
    }
    Log().info("training data '{}': {} frames", dataset, training->frames.size());
    loader = MakeLoader(core_options.method, options->loader, training);
    core_ = std::make_unique<SynthesizerCore>(core_options, loader, coverage);
    core_->SetCountHook([this](const std::string& key, uint64_t n) { Count(key, n); });
    if (!learned_ && !training->frames.empty()) {
      core_->LoadNow({0, "", core_options.method});
    } else if (learned_ && !checkpoint.empty()) {
      core_->LoadNow({0, checkpoint, core_options.method});
    }
  } catch (const std::invalid_argument& e) {
    throw runtime::StartupError(e.what());
  }
  if (core_->HasModel()) {
    Log().info("serving method {} (model version {})", core_options.method,
               core_->CurrentVersion());
  } else {
    Log().info("method {}: waiting for a ModelVersion on model_version", core_options.method);
  }
}

void SynthesizerNode::ServeRender() {
  Serve<msgs::pb::RenderRequest, msgs::RenderReplyMsg>(
      "render", [this](const msgs::pb::RenderRequest& request, msgs::RenderReplyMsg* reply,
                       std::string*) {
        core_->HandleRender(request, SynthesizerCore::Clock::now(), reply);
        if (!reply->meta.ok()) WarnThrottled("render", "render request refused: " +
                                                           reply->meta.error());
        return true;  // refusals are replies (ok = false), not transport errors
      });
}

void SynthesizerNode::StartTopicMode() {
  views_pub_ = Advertise<msgs::View>("views");
  topic_ = std::make_unique<TopicRenderer>(core_.get(), [this](msgs::View&& view) {
    views_pub_->Publish(view);
  });
  runtime::SubscriberOptions sub_options;
  sub_options.latest_only = true;
  SubscribeRaw(
      "planned_poses",
      [this](msgs::WireMessage&& wire, const msgs::pb::Header& header) {
        return OnPlannedPose(std::move(wire), header);
      },
      sub_options);
}

void SynthesizerNode::SubscribeModelVersions() {
  Subscribe<msgs::pb::ModelVersion>("model_version", [this](const msgs::pb::ModelVersion& mv) {
    // Versions of another method (a P2I-NET trainer and a fusion mapper on one topic) are not
    // this synthesizer's to load.
    if (!VersionIsFor(mv.method(), core_->options().method)) {
      Count("versions_other_method");
      WarnThrottled("version_method", "ignoring model version " + std::to_string(mv.version()) +
                                          " of method '" + mv.method() + "' (this synthesizer "
                                          "serves " + core_->options().method + ")");
      return;
    }
    ModelSpec spec{mv.version(), mv.checkpoint_path(), core_->options().method,
                   mv.poses_path()};
    if (core_->SwapAsync(spec)) {
      Log().info("loading model version {} from {} in the background", mv.version(),
                 mv.checkpoint_path());
    }
  });
}

void SynthesizerNode::StartStatusTimer() {
  AddTimer(std::chrono::milliseconds(500), [this] {
    const std::string swap_error = core_->LastSwapError();
    if (swap_error != last_swap_error_) {
      last_swap_error_ = swap_error;
      Log().warn("hot swap failed, still serving version {}: {}", core_->CurrentVersion(),
                 swap_error);
    }
    SetValue("model_version", static_cast<double>(core_->CurrentVersion()));
    SetValue("has_model", core_->HasModel() ? 1.0 : 0.0);
  });
}

SynthesizerNode::~SynthesizerNode() {
  if (topic_) topic_->Stop();
}

void SynthesizerNode::OnShutdown() {
  if (topic_) topic_->Stop();
}

bool SynthesizerNode::OnPlannedPose(msgs::WireMessage&& wire, const msgs::pb::Header& header) {
  PoseJob job;
  job.receipt = SynthesizerCore::Clock::now();
  std::string error;
  if (header.type() == msgs::pb::POSE_REQUEST) {
    msgs::pb::PoseRequest request;
    if (!msgs::Decode(wire, &request, &error)) {
      WarnThrottled("planned_poses", "dropping undecodable PoseRequest: " + error);
      return false;
    }
    job.pose = request.pose();
    job.request_id = request.request_id();
    job.deadline_ns = request.deadline_ns();
  } else if (header.type() == msgs::pb::POSE) {
    msgs::pb::PoseStamped stamped;
    if (!msgs::Decode(wire, &stamped, &error)) {
      WarnThrottled("planned_poses", "dropping undecodable PoseStamped: " + error);
      return false;
    }
    job.pose = stamped.pose();
    job.request_id = stamped.header().seq();
  } else {
    WarnThrottled("planned_poses", std::string("planned_poses: ignoring a ") +
                                       msgs::TypeName(header.type()) +
                                       " (expected PoseRequest or PoseStamped)");
    return false;
  }
  topic_->Submit(std::move(job));
  return true;
}

}  // namespace p2i::nodes
