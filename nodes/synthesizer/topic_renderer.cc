/// @file topic_renderer.cc
/// @brief TopicRenderer worker loop.
#include "nodes/synthesizer/topic_renderer.h"

#include <chrono>
#include <utility>

#include "nodes/runtime/publisher.h"

namespace p2i::nodes {

TopicRenderer::TopicRenderer(SynthesizerCore* core, std::function<void(msgs::View&&)> publish)
    : core_(core), publish_(std::move(publish)) {
  worker_ = std::thread([this] { Loop(); });
}

TopicRenderer::~TopicRenderer() { Stop(); }

void TopicRenderer::Stop() {
  stop_ = true;
  slot_.Close();
  if (worker_.joinable()) worker_.join();
}

void TopicRenderer::Submit(PoseJob job) {
  ++outstanding_;
  if (slot_.Put(std::move(job))) {
    core_->Count("skipped");
    --outstanding_;
  }
}

void TopicRenderer::Loop() {
  while (!stop_) {
    std::optional<PoseJob> job = slot_.Take(std::chrono::milliseconds(100));
    if (!job) continue;
    if (job->deadline_ns > 0 && runtime::NowNs() > job->deadline_ns) {
      core_->Count("expired");
      --outstanding_;
      continue;
    }
    msgs::View view;
    std::string error;
    if (core_->RenderView(job->pose, job->receipt, &view, &error)) {
      msgs::pb::Header* h = view.meta.mutable_header();
      h->set_request_id(job->request_id);
      h->set_capture_stamp_ns(runtime::NowNs());
      h->set_frame_id(job->pose.child_frame().empty() ? "camera" : job->pose.child_frame());
      try {
        publish_(std::move(view));
        ++rendered_;
      } catch (const std::exception&) {
        core_->Count("topic_failures");  // e.g. the socket closed during shutdown
      }
    } else {
      core_->Count("topic_failures");
    }
    --outstanding_;
  }
}

}  // namespace p2i::nodes
