/// @file slam_sink.h
/// @brief The SLAM-augmentation sink's logic: check, write, account, summarise (no sockets).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "nodes/slam_sink/odometry_checker.h"
#include "nodes/slam_sink/sequence_tracker.h"
#include "nodes/slam_sink/sink_frame.h"
#include "nodes/slam_sink/slam_sink_options.h"
#include "nodes/slam_sink/tum_sequence_writer.h"
#include "scene/camera_info.h"

namespace p2i::slam_sink {

/// Takes frames as they arrive: accounts their sequence numbers per source, checks synthetic
/// frames with OdometryChecker (when enabled and a camera is known), applies the policy (flag:
/// write and mark; drop: do not write failing frames) and writes them with TumSequenceWriter.
/// Close() finalises the sequence and writes summary.json. The views' calibration, once known,
/// is written as out_dir/camera_info.yaml (ROS format) for readers of the sequence. A frame is "acknowledged" when
/// Process() returns with written = true: its files are then on disk and listed.
///
/// Thread-compatible: one thread calls everything.
class SlamSink {
 public:
  struct Outcome {
    bool written = false;
    bool duplicate = false;  ///< same (source, seq) seen before: not written again
    CheckResult check;       ///< kUnchecked for real frames or when checking is off
    SequenceTracker::Outcome sequence = SequenceTracker::Outcome::kFirst;
    uint64_t gap = 0;        ///< seq numbers skipped just before this frame
    WrittenFiles files;
  };

  /// `camera`: the intrinsics of the synthetic views; without it the check is off (logged in the
  /// summary as check_enabled = false). Throws like TumSequenceWriter / OdometryChecker.
  SlamSink(SlamSinkOptions options, std::optional<scene::CameraInfo> camera);

  /// Provides the intrinsics later (e.g. from a latched camera_info topic); enables the check
  /// from the next frame on if checking is on and no camera was given yet. Returns whether this
  /// call enabled it.
  bool SetCamera(const scene::CameraInfo& camera);

  /// Throws std::runtime_error on an I/O error (the frame is then not acknowledged).
  Outcome Process(const SinkFrame& frame);

  /// Flushes the index files (cheap).
  void Flush() { writer_.Flush(); }
  /// Finalises the index files and writes summary.json (atomically). Idempotent.
  void Close();

  /// Everything the summary reports (see docs/SLAM_SINK.md).
  nlohmann::json Summary() const;
  /// Writes Summary() to out_dir/summary.json via temp + rename.
  void WriteSummary() const;
  /// A one-line human summary for the log.
  std::string SummaryLine() const;

  const SequenceTracker& sequences() const { return tracker_; }
  const TumSequenceWriter& writer() const { return writer_; }
  const OdometryChecker* checker() const { return checker_.get(); }

 private:
  void WriteCamera(const scene::CameraInfo& camera);

  SlamSinkOptions options_;
  TumSequenceWriter writer_;
  std::unique_ptr<OdometryChecker> checker_;
  SequenceTracker tracker_;
  uint64_t received_ = 0;
  uint64_t duplicates_ = 0;
  uint64_t synthetic_written_ = 0;
  uint64_t real_written_ = 0;
  uint64_t real_skipped_ = 0;
  uint64_t flagged_ = 0;
  uint64_t dropped_ = 0;
  uint64_t write_errors_ = 0;
  bool camera_written_ = false;
  std::pair<int, int> camera_size_{0, 0};  // width, height of camera_info.yaml
  scene::CameraInfo camera_;               // as given (rescaled to the first view's size)
  uint64_t written_frames_ = 0;            // frames past the size check
  bool closed_ = false;
};

}  // namespace p2i::slam_sink
