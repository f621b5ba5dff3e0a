/// @file topic_renderer.h
/// @brief Topic mode: renders the newest planned pose on a worker thread, skipping stale ones.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "msgs/codec.h"
#include "nodes/synthesizer/latest_slot.h"
#include "nodes/synthesizer/synthesizer_core.h"

namespace p2i::nodes {

/// One planned pose waiting to be rendered.
struct PoseJob {
  msgs::pb::Pose pose;
  uint64_t request_id = 0;
  int64_t deadline_ns = 0;  ///< wall clock ns since epoch; 0 = none
  SynthesizerCore::Clock::time_point receipt;
};

/// Latest-only rendering of planned poses. Submit() (the subscription callback: cheap, never
/// blocks on a render) puts the job into a one-element slot; a worker thread takes the newest
/// job, renders it with the SynthesizerCore and hands the View to `publish`. A job replaced
/// before the worker took it is counted `skipped` on the core; a job whose deadline passed
/// before rendering is counted `expired`; a failed render `topic_failures`. So, over a run:
/// submitted = rendered + skipped + expired + failed (+ at most one pending).
///
/// Thread-safety: Submit() from any thread; `publish` runs on the worker thread. Stop() (also
/// in the destructor) joins the worker.
class TopicRenderer {
 public:
  TopicRenderer(SynthesizerCore* core, std::function<void(msgs::View&&)> publish);
  ~TopicRenderer();
  TopicRenderer(const TopicRenderer&) = delete;
  TopicRenderer& operator=(const TopicRenderer&) = delete;

  void Submit(PoseJob job);
  void Stop();
  uint64_t Rendered() const { return rendered_.load(); }
  /// True when no job is pending and none is being rendered.
  bool Idle() const { return outstanding_.load() == 0; }

 private:
  void Loop();

  SynthesizerCore* core_;
  std::function<void(msgs::View&&)> publish_;
  LatestSlot<PoseJob> slot_;
  std::atomic<bool> stop_{false};
  std::atomic<int64_t> outstanding_{0};  ///< submitted and not yet finished or skipped
  std::atomic<uint64_t> rendered_{0};
  std::thread worker_;
};

}  // namespace p2i::nodes
