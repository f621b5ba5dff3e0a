/// @file synthesizer_node.cc
/// @brief SynthesizerNode: parameters, endpoints, wiring to SynthesizerCore.
#include "nodes/synthesizer/synthesizer_node.h"

#include <stdexcept>

#include "model/coverage.h"
#include "nodes/synthesizer/method_loader.h"

namespace p2i::nodes {

SynthesizerNode::SynthesizerNode(const runtime::NodeArgs& args)
    : runtime::Node("synthesizer", args) {
  SynthesizerCoreOptions core_options;
  core_options.method =
      Declare<std::string>("method", "p2i", "p2i | cnn (checkpoint) | nearest | warp (dataset)");
  const std::string checkpoint = Declare<std::string>(
      "checkpoint", "", "learned methods: start-up checkpoint; '' = wait for model_version");
  const std::string dataset = Declare<std::string>(
      "dataset", "builtin:small_office",
      "training data: frames for nearest/warp, poses for the coverage score; a dataset folder, "
      "builtin:NAME (default arm sweep rendered at width x height) or '' (coverage 0)");
  const int width = Declare<int>("width", 64, "resolution of built-in/resized training data");
  const int height = Declare<int>("height", 64, "resolution of built-in/resized training data");
  const int stride = Declare<int>("dataset_stride", 1, "keep every N-th training frame");
  LoaderOptions loader_options;
  loader_options.threads = Declare<int>("threads", 2, "torch threads (learned methods)");
  loader_options.warp_k = Declare<int>("warp_k", 4, "warp: source frames per view");
  loader_options.warp_fill_holes = Declare<bool>("warp_fill_holes", true, "warp: fill holes");
  core_options.max_poses = Declare<int>("max_poses", 256, "most poses in one RenderRequest");
  core_options.max_batch = Declare<int>("max_batch", 16, "poses per network batch");
  const bool topic_mode =
      Declare<bool>("topic_mode", true, "render planned_poses onto views (latest-only)");

  learned_ = core_options.method == "p2i" || core_options.method == "cnn";
  std::shared_ptr<const model::CoverageScorer> coverage;
  SynthesizerLoader loader;
  try {
    auto training = std::make_shared<const scene::RgbdDataset>(
        LoadTrainingData(dataset, width, height, /*with_frames=*/!learned_, stride));
    if (!training->frames.empty()) {
      std::vector<scene::Pose> poses;
      poses.reserve(training->frames.size());
      for (const auto& f : training->frames) poses.push_back(f.pose);
      coverage = std::make_shared<const model::CoverageScorer>(std::move(poses));
    }
    Log().info("training data '{}': {} frames", dataset, training->frames.size());
    loader = MakeLoader(core_options.method, loader_options, training);
    core_ = std::make_unique<SynthesizerCore>(core_options, loader, coverage);
    core_->SetCountHook([this](const std::string& key, uint64_t n) { Count(key, n); });
    if (!learned_) {
      core_->LoadNow({0, "", core_options.method});
    } else if (!checkpoint.empty()) {
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

  Serve<msgs::pb::RenderRequest, msgs::RenderReplyMsg>(
      "render", [this](const msgs::pb::RenderRequest& request, msgs::RenderReplyMsg* reply,
                       std::string*) {
        core_->HandleRender(request, SynthesizerCore::Clock::now(), reply);
        if (!reply->meta.ok()) WarnThrottled("render", "render request refused: " +
                                                           reply->meta.error());
        return true;  // refusals are replies (ok = false), not transport errors
      });

  if (topic_mode) {
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
  if (learned_) {
    Subscribe<msgs::pb::ModelVersion>("model_version", [this](const msgs::pb::ModelVersion& mv) {
      ModelSpec spec{mv.version(), mv.checkpoint_path(), core_->options().method,
                     mv.poses_path()};
      if (core_->SwapAsync(spec)) {
        Log().info("loading model version {} from {} in the background", mv.version(),
                   mv.checkpoint_path());
      }
    });
  }
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
