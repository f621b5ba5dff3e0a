/// @file refine_tuner.h
/// @brief Online fine-tuning of the `fusion` method's learned refinement (issue 12 point 4): the
/// mapper offers its newest keyframes after each published version; on its own thread the tuner
/// renders them leave-one-out (refine/leave_one_out.h: each frame from a scene fused without
/// it), runs Adam steps on the refinement (its optimiser state kept from round to round) and
/// writes the net atomically to a new file per round, which the mapper copies into its next
/// version (the file of the round before stays, so a copy in progress never sees it go). The
/// mapping thread never waits for it: a round still running when the next keyframes are offered
/// takes them afterwards (latest only, the older offer is dropped).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fusion/fusion_scene.h"
#include "model/refine_options.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace p2i::model {
class LearnedRefiner;
}  // namespace p2i::model

namespace p2i::trainer {

struct RefineTunerOptions {
  /// The refinement to start from (a `p2i refine train-sim` file such as models/refine_sim.pt);
  /// "" = a fresh net (identity on the blend). Each mapping session starts from it again.
  std::string net;
  /// How the leave-one-out folds are fused and blended: the mapper's scene options (its blend k
  /// is the net's layout).
  fusion::FusionSceneOptions scene;
  int steps_per_round = 100;    ///< Adam steps per round (one round per offered keyframe set)
  int window_keyframes = 48;    ///< the newest keyframes of an offer that a round uses
  int min_keyframes = 8;        ///< offers with fewer keyframes are skipped (counted)
  /// Samples are rendered at the frame camera scaled to this width (its aspect kept).
  int view_width = 160;
  int folds = 4;                ///< refine::LeaveOneOutOptions::folds
  /// lr, batch_size, crop, ssim_weight, depth_weight, seed (steps from steps_per_round).
  model::RefineTrainOptions train;
  /// Round r's net is written (tmp + rename) to out_dir/online_refine_<r, 6 digits>.pt; the
  /// files of rounds before r - 1 are removed.
  std::string out_dir;
  /// Throws std::invalid_argument naming the field and its value.
  void Validate() const;
};

/// Thread-safety: every public member may be called from any thread.
class RefineTuner {
 public:
  struct Stats {
    uint64_t rounds = 0;          ///< rounds finished (a net written)
    uint64_t offers_skipped = 0;  ///< offers with too few keyframes or no usable sample
    int64_t total_steps = 0;      ///< Adam steps the written net has seen (a loaded net's included)
    int last_samples = 0;         ///< leave-one-out samples of the last round
    double first_loss = 0.0;      ///< the last round's mean loss over its first steps ...
    double last_loss = 0.0;       ///< ... and over its last steps
    double last_round_s = 0.0;    ///< wall time of the last round (fusing folds + steps + save)
    std::string last_error;
  };

  /// Loads `options.net` (or makes a fresh net) and starts the tuning thread. Throws
  /// std::invalid_argument on bad options and std::runtime_error on an unreadable net.
  explicit RefineTuner(RefineTunerOptions options);
  ~RefineTuner();  ///< Stop()

  /// The keyframes to tune on next: the newest window_keyframes of `keyframes` (their images are
  /// shared, not copied: the caller must not modify them). Replaces an offer not yet taken.
  void Offer(const std::vector<scene::RgbdSample>& keyframes, const scene::CameraInfo& camera);
  /// The newest fine-tuned net: its file ("" until the first round has finished) and the Adam
  /// steps it has seen.
  struct Net {
    std::string path;
    int64_t steps = 0;
  };
  Net LatestNet() const;
  /// Blocks until `rounds` rounds have finished or `timeout_s` passed; returns whether they had.
  bool WaitForRounds(uint64_t rounds, double timeout_s) const;
  Stats GetStats() const;
  /// Ends the thread; a round in progress stops between two steps and writes nothing.
  void Stop();

 private:
  void Run();
  void Round(const scene::RgbdDataset& frames);
  std::string NetPath(uint64_t round) const;

  RefineTunerOptions options_;
  std::unique_ptr<model::LearnedRefiner> refiner_;  // tuning thread only (after construction)

  mutable std::mutex mutex_;
  mutable std::condition_variable cv_;
  std::optional<scene::RgbdDataset> pending_;
  bool stopping_ = false;
  Stats stats_;
  Net latest_;
  std::thread thread_;
};

}  // namespace p2i::trainer
