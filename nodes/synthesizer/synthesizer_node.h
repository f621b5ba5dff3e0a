/// @file synthesizer_node.h
/// @brief The synthesizer node: render service, topic mode and hot swap over SynthesizerCore.
#pragma once

#include <memory>
#include <string>

#include "nodes/runtime/node.h"
#include "nodes/synthesizer/synthesizer_core.h"
#include "nodes/synthesizer/topic_renderer.h"

namespace p2i::nodes {

struct SynthesizerOptions;

/// Serves "render" (RenderRequest -> RenderReplyMsg), renders planned poses from
/// "planned_poses" (PoseRequest or PoseStamped, latest-only) onto "views" (View), and hot-swaps
/// models announced on "model_version" (learned methods). See docs/SYNTHESIZER.md for the
/// parameters.
///
/// Thread-safety: like every Node, constructed and spun on one thread. Topic-mode renders run
/// on the TopicRenderer worker, hot-swap loads on the core's loader thread.
class SynthesizerNode : public runtime::Node {
 public:
  explicit SynthesizerNode(const runtime::NodeArgs& args);
  ~SynthesizerNode() override;

 protected:
  void OnShutdown() override;

 private:
  // Start-up steps of the constructor, after the parameters are read and validated.
  void StartCore(SynthesizerOptions* options);  // training data, loader, core, first model
  void ServeRender();                           // the render service
  void StartTopicMode();                        // planned_poses -> views
  void SubscribeModelVersions();                // hot swaps (learned methods, fusion)
  void StartStatusTimer();                      // model_version / has_model, swap errors

  bool OnPlannedPose(msgs::WireMessage&& wire, const msgs::pb::Header& header);

  std::unique_ptr<SynthesizerCore> core_;
  std::shared_ptr<runtime::Publisher<msgs::View>> views_pub_;
  std::unique_ptr<TopicRenderer> topic_;
  bool learned_ = false;
  bool versioned_ = false;  ///< hot-swaps ModelVersions: learned, or MethodInfo::loads_versions
  std::string last_swap_error_;  ///< logged once per new failure
};

}  // namespace p2i::nodes
