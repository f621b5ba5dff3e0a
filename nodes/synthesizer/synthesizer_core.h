/// @file synthesizer_core.h
/// @brief The synthesizer node's logic without sockets: render requests over a hot-swappable
/// ViewSynthesizer, with per-view model version, coverage and timings.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "model/coverage.h"
#include "model/view_synthesizer.h"
#include "msgs/codec.h"
#include "scene/pose.h"

namespace p2i::nodes {

/// Which model to load: the ModelVersion fields the synthesizer uses.
struct ModelSpec {
  uint64_t version = 0;         ///< 0 = the start-up model (checkpoint parameter)
  std::string checkpoint_path;  ///< learned methods; ignored by nearest/warp
  std::string method;           ///< a name of model/method_registry.h
  /// TUM file with the poses the model was trained on (ModelVersion.poses_path): the coverage
  /// score of this model's views is computed against them. "" = the core's start-up coverage.
  std::string poses_path = "";  // (initializer: {version, path, method} stays warning-free)
};

/// Builds a synthesizer for a spec; throws (any std::exception) when it cannot. Runs on the
/// background loader thread for hot swaps, so it must not touch the serving thread's state.
using SynthesizerLoader =
    std::function<std::unique_ptr<model::ViewSynthesizer>(const ModelSpec& spec)>;

struct SynthesizerCoreOptions {
  std::string method = "p2i";  ///< reported in every view; a request naming another is refused
  int max_poses = 256;         ///< poses per RenderRequest; more is a bad request
  int max_batch = 16;          ///< poses per RenderBatch call (learned methods batch them)
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

/// Serves render requests from the current model and swaps models in the background.
///
/// Hot swap: SwapAsync() hands a spec to a loader thread (latest wins when several arrive
/// during one load; versions not newer than the current or pending one are ignored and counted
/// `stale_versions`). When the load succeeds the model pointer is replaced under a mutex; a
/// request takes its own reference to the model when it starts, so it renders every view with
/// one model (one model_version per request), and requests already running finish on the old
/// model. The serving thread never loads: it waits at most for the mutex around a pointer copy
/// (and for a render of the same model already running on another thread). A failed load is
/// counted (`swap_failures`) and the old model keeps serving.
///
/// Counters (Counter(), and the hook set by SetCountHook): requests, views, bad_requests,
/// no_model, expired, render_errors, swaps, swap_failures, stale_versions.
///
/// Thread-safety: thread-safe. HandleRender/RenderView may be called from several threads;
/// renders of one model are serialised by a per-model mutex (ViewSynthesizer is not
/// thread-safe). The loader callback runs on the internal loader thread.
class SynthesizerCore {
 public:
  using Clock = std::chrono::steady_clock;

  /// `coverage` may be null: coverage is then reported as 0. Throws std::invalid_argument on
  /// invalid options or an empty loader.
  SynthesizerCore(SynthesizerCoreOptions options, SynthesizerLoader loader,
                  std::shared_ptr<const model::CoverageScorer> coverage);
  /// Stops and joins the loader thread (an in-progress load finishes first).
  ~SynthesizerCore();
  SynthesizerCore(const SynthesizerCore&) = delete;
  SynthesizerCore& operator=(const SynthesizerCore&) = delete;

  /// Loads synchronously on the calling thread and installs the model (start-up). Throws what
  /// the loader throws.
  void LoadNow(const ModelSpec& spec);
  /// Queues a background load; returns at once. False when ignored as stale.
  bool SwapAsync(const ModelSpec& spec);
  /// Waits until a model with version >= `version` serves, or the timeout. For tests/tools.
  bool WaitForVersion(uint64_t version, std::chrono::milliseconds timeout) const;
  bool HasModel() const;
  /// Version of the serving model (0 also when there is none; see HasModel()).
  uint64_t CurrentVersion() const;
  /// True while the loader thread is building a model.
  bool Loading() const { return loading_.load(); }

  /// Answers a RenderRequest received at `receipt`. Never throws: a bad request (no poses, too
  /// many, a non-finite pose or quaternion that is not unit length, another method, a passed
  /// deadline) or a render failure gives meta.ok = false with a one-line error and no images.
  void HandleRender(const msgs::pb::RenderRequest& request, Clock::time_point receipt,
                    msgs::RenderReplyMsg* reply);
  /// Renders one view (topic mode). False with `error` set on failure; never throws.
  bool RenderView(const msgs::pb::Pose& pose, Clock::time_point receipt, msgs::View* view,
                  std::string* error);

  uint64_t Counter(const std::string& key) const;
  /// Adds to a counter (also forwarded to the hook).
  void Count(const std::string& key, uint64_t n = 1);
  /// Why the last failed hot-swap load failed ("" if none did). Thread-safe.
  std::string LastSwapError();
  /// Also forwards every counter increment to `hook` (e.g. Node::Count). Set before serving.
  void SetCountHook(std::function<void(const std::string&, uint64_t)> hook);
  const SynthesizerCoreOptions& options() const { return options_; }

  /// Checks a pose message by the codec's rule (msgs::ValidatePose: finite, quaternion norm
  /// within msgs::kQuaternionTolerance of 1) and converts it once (normalised) into *out. False
  /// with a reason naming `field` otherwise.
  static bool ToScenePose(const msgs::pb::Pose& pose, const std::string& field, scene::Pose* out,
                          std::string* why);

 private:
  struct Loaded {
    ModelSpec spec;
    std::unique_ptr<model::ViewSynthesizer> synth;
    std::shared_ptr<const model::CoverageScorer> coverage;  ///< null = none (coverage 0)
    std::mutex render_mutex;
  };
  /// One rendered view before encoding.
  struct Rendered {
    scene::RgbdSample view;
    double queue_ms = 0.0;
    double render_ms = 0.0;
    std::optional<model::ViewGeometry> geometry;  ///< methods with scene geometry (fusion)
  };

  std::shared_ptr<Loaded> Current() const;
  void Install(std::shared_ptr<Loaded> loaded);
  void LoaderLoop();
  /// The coverage of a model: from spec.poses_path when given and readable, else the start-up
  /// one (counted `coverage_fallbacks`, reason in LastSwapError()). Loader thread / LoadNow.
  std::shared_ptr<const model::CoverageScorer> CoverageFor(const ModelSpec& spec);
  /// Renders `poses` with one model in chunks of max_batch. Throws on render failure.
  std::vector<Rendered> RenderWith(Loaded* loaded, const std::vector<scene::Pose>& poses,
                                   Clock::time_point receipt);
  /// `pose_msg` is copied into the metadata as received; `pose` is its conversion (coverage).
  void FillMeta(const Loaded& loaded, const msgs::pb::Pose& pose_msg, const scene::Pose& pose,
                const Rendered& r, msgs::pb::ViewMeta* meta) const;

  SynthesizerCoreOptions options_;
  SynthesizerLoader loader_;
  std::shared_ptr<const model::CoverageScorer> coverage_;

  mutable std::mutex model_mutex_;
  mutable std::condition_variable model_cv_;
  std::shared_ptr<Loaded> current_;

  std::mutex pending_mutex_;
  std::condition_variable pending_cv_;
  std::optional<ModelSpec> pending_;
  uint64_t newest_requested_ = 0;
  std::string last_swap_error_;
  bool stop_ = false;
  std::atomic<bool> loading_{false};
  std::thread loader_thread_;

  mutable std::mutex counters_mutex_;
  std::map<std::string, uint64_t> counters_;
  std::function<void(const std::string&, uint64_t)> count_hook_;
};

}  // namespace p2i::nodes
