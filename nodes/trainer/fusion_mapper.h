/// @file fusion_mapper.h
/// @brief The trainer node's `fusion` method: online mapping. Every camera frame is integrated
/// into a TSDF as it arrives; frames far enough from the keyframes so far are appended to an
/// append-only keyframe capture; every `publish_every_frames` integrated frames the TSDF is
/// written as a committed model version (model/fusion_version.h) that the synthesizer hot-swaps.
/// The mapping thread only copies the volumes for a version (milliseconds); a writer thread
/// writes it (~0.5 s for a room), so a camera's frames keep being integrated meanwhile.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "fusion/fusion_scene.h"
#include "model/fusion_version.h"
#include "nodes/trainer/refine_tuner.h"
#include "scene/camera_info.h"
#include "scene/rgbd_sample.h"

namespace p2i::scene {
class CaptureWriter;
}  // namespace p2i::scene

namespace p2i::fusion {
struct SceneVersionSnapshot;
}  // namespace p2i::fusion

namespace p2i::trainer {

struct FusionMapperOptions {
  fusion::FusionSceneOptions scene;  ///< TSDF (voxel size, ...) and keyframe choice
  /// keyframes_sNNNNNN/ (one append-only capture per mapping session) and versions/ go here.
  std::string work_dir;
  int publish_every_frames = 30;  ///< integrated frames between published versions
  int keep_versions = 3;          ///< committed versions kept on disk (older ones pruned)
  /// ... and none pruned until it is this old: a synthesizer told of a version finds it even when
  /// loading takes longer than a few publish periods (seen on a busy 2-core box: every version it
  /// started loading was pruned first, and it never swapped). Costs up to keep_seconds x the
  /// publish rate versions of disk.
  double keep_seconds = 10.0;
  /// Frames waiting for integration; when a new one arrives to a full queue the oldest is
  /// dropped (counted): a camera faster than integration is mapped at integration's rate.
  int queue_frames = 2;
  /// A refinement file (`p2i refine train-sim` output) copied into every version; "" = none.
  std::string refine_net;
  /// > 0: the refinement (refine_net, or a fresh net when "") is fine-tuned online on its own
  /// thread (refine_tuner.h), this many Adam steps per round, one round per published version
  /// on the newest keyframes; each version carries the newest fine-tuned net (refine_net until
  /// the first round has finished). 0 = refine_net as it is.
  int refine_finetune_steps = 0;
  int refine_window_keyframes = 48;  ///< RefineTunerOptions::window_keyframes
  int refine_view_width = 160;       ///< RefineTunerOptions::view_width
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
  /// The fine-tuning's options: refine_net, scene, refine_* and the nets' folder work_dir/refine.
  RefineTunerOptions TunerOptions() const;
};

/// Thread-safety: Submit and GetStats from any thread; integration runs on the mapper's own
/// thread, version writing on a writer thread of its own, one version at a time; `on_version` is
/// called on the writer thread, in version order.
class FusionMapper {
 public:
  /// Called after each committed version, with its folder.
  using VersionCallback =
      std::function<void(const model::FusionVersionManifest& manifest, const std::string& dir)>;

  struct Stats {
    uint64_t received = 0;     ///< frames submitted
    uint64_t integrated = 0;   ///< frames fused into the TSDF
    uint64_t keyframes = 0;    ///< frames kept as colour sources
    uint64_t dropped = 0;      ///< frames dropped from a full queue
    uint64_t rejected = 0;     ///< frames refused (camera changed, bad images)
    uint64_t versions = 0;     ///< versions written by this mapper
    uint64_t last_version = 0;
    double last_integrate_ms = 0.0;
    std::string last_error;    ///< of the last rejected frame or failed version write
    // Online fine-tuning of the refinement (refine_finetune_steps > 0; else all 0):
    uint64_t refine_rounds = 0;       ///< rounds finished
    int64_t refine_steps = 0;         ///< Adam steps the newest fine-tuned net has seen
    double refine_loss = 0.0;         ///< the last round's loss over its last steps
    std::string refine_error;         ///< why the last offer was not tuned ("" after a round)
  };

  /// Starts the mapping thread. Version numbers continue after the highest committed one in
  /// work_dir/versions (a synthesizer that served them takes the new ones as newer); the map
  /// itself starts empty. Throws std::invalid_argument on bad options.
  FusionMapper(FusionMapperOptions options, VersionCallback on_version);
  ~FusionMapper();  ///< Stop()

  /// Queues one frame (rgb CV_8UC3, depth CV_32FC1 metres, pose camera-to-world) of `camera`.
  /// With `wait`, blocks while the queue is full instead of dropping (offline data), and a
  /// version due at this frame waits for the one being written, so versions fall every
  /// publish_every_frames frames exactly. Without it (a camera), a version due while another is
  /// being written is taken at the first frame after that write.
  void Submit(scene::RgbdSample frame, const scene::CameraInfo& camera, bool wait = false);
  /// Integrates what is queued, writes a last version when frames were integrated since the
  /// previous one, and ends the thread (and the fine-tuning's: a round in progress is dropped).
  /// Idempotent.
  void Stop();
  Stats GetStats() const;
  const std::string& VersionsDir() const { return versions_dir_; }

 private:
  struct Job {
    scene::RgbdSample frame;
    scene::CameraInfo camera;
    bool wait = false;
  };
  void Run();
  void Integrate(const Job& job);
  /// Snapshots the scene for the writer thread (mapping thread). When a version is being written
  /// it returns at once, unless `wait`, which waits for that write first.
  void Publish(bool wait);
  bool RetryDue() const;
  void WriteVersions();  // the writer thread
  void Prune();

  FusionMapperOptions options_;
  VersionCallback on_version_;
  std::string versions_dir_;
  std::string keyframes_dir_;
  uint64_t next_version_ = 1;

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> queue_;
  bool stopping_ = false;
  Stats stats_;

  // Mapping thread only.
  std::unique_ptr<fusion::FusionScene> scene_;
  std::unique_ptr<scene::CaptureWriter> keyframes_;
  std::unique_ptr<RefineTuner> tuner_;  // set when refine_finetune_steps > 0
  int64_t published_refine_steps_ = 0;  // of the fine-tuned net in the newest version
  uint64_t unpublished_ = 0;
  std::thread thread_;

  // Under mutex_: the writer thread's work and what it sets after a write.
  std::condition_variable write_cv_;
  std::unique_ptr<fusion::SceneVersionSnapshot> pending_;  // the version to write next
  uint64_t pending_frames_ = 0;   // frames integrated since the version before it
  bool writing_ = false;          // a snapshot is pending or being written
  bool writer_stop_ = false;
  uint64_t retry_frames_ = 0;     // a failed write's frames, published again with the next one
  bool retry_ = false;            // the last write failed: publish again at the next chance
  std::string last_version_dir_;  // the newest version written: its unchanged submaps are reused
  std::thread writer_;
};

}  // namespace p2i::trainer
