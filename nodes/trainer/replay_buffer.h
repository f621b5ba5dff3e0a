/// @file replay_buffer.h
/// @brief The trainer's bounded, disk-persisted replay buffer: a recent window plus a reservoir
/// sample of older frames, stored at the model's training resolution.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "scene/capture.h"
#include "scene/rgbd_sample.h"

namespace p2i::trainer {

/// Bounded store of posed RGB-D frames for online training.
///
/// Policy: capacity C = floor(max_mb MiB / bytes per frame) (at least 2), where a frame costs
/// width * height * (3 + 4) bytes (RGB8 + float depth). The newest R = ceil(C * recent_fraction)
/// accepted frames form the recent window; a frame that leaves the window is offered to a
/// reservoir of C - R older frames by reservoir sampling (Vitter's algorithm R), so the
/// reservoir is a uniform sample of everything that ever left the window. The training set thus
/// keeps the latest views (the robot's current surroundings) and a fair memory of older ones.
///
/// Frames are centre-cropped and resized to width x height on arrival (scene/image_ops.h);
/// the camera is the first frame's, cropped/scaled likewise. Frames without a pose are counted
/// (DroppedNoPose) and dropped.
///
/// Persistence (if `dir` is set): every accepted frame is appended to a p2i capture folder
/// `dir/gen_NNNNNN` (scene/capture.h, atomic per frame), then `dir/buffer_state.yaml` (atomic,
/// the commit point) records which capture indices are in the window and the reservoir. When
/// the capture holds 2 C frames it is compacted into the next generation folder (the buffer's
/// frames only), the state is switched to it, and the old folder is removed. On construction
/// the buffer reloads the state and its frames; frames appended after the last state write
/// (a crash in between) are replayed through the policy. Nothing accepted is lost on restart.
///
/// Thread-safety: thread-safe (one internal mutex); Snapshot() returns shallow copies of the
/// immutable images, so training may read them while new frames arrive.
class ReplayBuffer {
 public:
  struct Options {
    std::string dir;               ///< persistence folder; "" = in memory only
    double max_mb = 256.0;         ///< memory bound for the stored images (MiB)
    double recent_fraction = 0.5;  ///< share of the capacity kept as the recent window
    int width = 64;                ///< training resolution
    int height = 64;
    uint64_t seed = 1;             ///< reservoir sampling

    /// Throws std::invalid_argument naming the bad field.
    void Validate() const;
  };

  explicit ReplayBuffer(const Options& options);
  ~ReplayBuffer();

  /// Adds one frame (any size; resized here). Returns false (and counts) if it has no pose.
  /// `has_pose` = false marks a frame whose sensor gave no pose.
  bool Add(const scene::RgbdSample& sample, const scene::CameraInfo& camera, bool has_pose = true);

  /// The current frames (reservoir first, then the window oldest to newest) and the camera.
  scene::RgbdDataset Snapshot() const;

  size_t Size() const;
  size_t Capacity() const { return capacity_; }
  size_t RecentCapacity() const { return recent_capacity_; }
  uint64_t Accepted() const;      ///< frames accepted since construction (not counting reload)
  uint64_t DroppedNoPose() const;
  size_t Reloaded() const { return reloaded_; }  ///< frames restored from disk at start
  static size_t BytesPerFrame(int width, int height) {
    return static_cast<size_t>(width) * height * 7;
  }

 private:
  struct Entry {
    scene::RgbdSample sample;
    size_t disk_index = 0;  ///< index in the current generation's capture
  };

  void Reload();
  void Insert(Entry entry);               // policy only (mutex held)
  void Persist(const scene::RgbdSample& s, Entry* entry);  // mutex held
  void WriteState();                      // mutex held
  void Compact();                         // mutex held
  std::string GenFolder(int generation) const;

  Options options_;
  size_t capacity_ = 2;
  size_t recent_capacity_ = 1;
  mutable std::mutex mutex_;
  bool have_camera_ = false;
  scene::CameraInfo camera_;
  std::deque<Entry> recent_;
  std::vector<Entry> reservoir_;
  uint64_t left_window_ = 0;  ///< frames that ever left the window (reservoir sampling count)
  std::mt19937_64 rng_;
  uint64_t accepted_ = 0;
  uint64_t dropped_no_pose_ = 0;
  size_t reloaded_ = 0;
  int generation_ = 0;
  std::unique_ptr<scene::CaptureWriter> writer_;
};

}  // namespace p2i::trainer
