/// @file synthesizer_node.h
/// @brief The synthesizer node: render service, topic mode and hot swap over SynthesizerCore.
#pragma once

#include <memory>
#include <string>

#include "nodes/runtime/node.h"
#include "nodes/synthesizer/synthesizer_core.h"
#include "nodes/synthesizer/topic_renderer.h"

namespace p2i::nodes {

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
  bool OnPlannedPose(msgs::WireMessage&& wire, const msgs::pb::Header& header);

  std::unique_ptr<SynthesizerCore> core_;
  std::shared_ptr<runtime::Publisher<msgs::View>> views_pub_;
  std::unique_ptr<TopicRenderer> topic_;
  bool learned_ = false;
  std::string last_swap_error_;  ///< logged once per new failure
};

}  // namespace p2i::nodes
