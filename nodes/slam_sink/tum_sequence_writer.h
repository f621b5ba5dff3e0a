/// @file tum_sequence_writer.h
/// @brief Crash-safe writer of a TUM RGB-D sequence folder (rgb/, depth/, rgb.txt, depth.txt,
/// groundtruth.txt, associations.txt) plus the sink's per-frame record frames.txt.
#pragma once

#include <cstddef>
#include <limits>
#include <set>
#include <string>

#include <opencv2/core.hpp>

#include "nodes/slam_sink/sink_frame.h"

namespace p2i::slam_sink {

struct TumSequenceWriterOptions {
  std::string out_dir;                ///< created if missing
  double depth_scale = 5000.0;        ///< depth PNG units per metre (TUM: 5000)
  bool write_associations = true;     ///< associations.txt as ORB-SLAM's rgbd_tum reads it
  bool fsync = false;                 ///< fsync images and index lines (power-loss safety)
  int png_compression = 1;            ///< 0..9; 1 is fast and still lossless
  /// false: an out_dir that already holds rgb.txt is an error (refuses to mix two runs);
  /// true: keep its lines and append.
  bool append = false;

  void Validate() const;
};

/// Per-frame annotations recorded in frames.txt (the check result; NaN = not computed).
struct FrameRecord {
  std::string check = "unchecked";  ///< pass | fail | unchecked
  double translation_error_m = std::numeric_limits<double>::quiet_NaN();
  double rotation_error_deg = std::numeric_limits<double>::quiet_NaN();
};

/// Where Write() put a frame's images (paths relative to out_dir, as listed in the index files).
struct WrittenFiles {
  std::string rgb;
  std::string depth;
};

/// Writes frames as a TUM RGB-D sequence that ORB-SLAM-style tools and scene::ReadTumRgbd read:
///   rgb/<stamp>[_syn].png      8-bit colour PNG
///   depth/<stamp>[_syn].png    16-bit PNG, depth_scale units per metre, 0 = invalid
///   rgb.txt, depth.txt         "timestamp filename" with the TUM comment header
///   groundtruth.txt            "timestamp tx ty tz qx qy qz qw" (the frame's pose; camera-to-world)
///   associations.txt           "t_rgb rgb/x.png t_depth depth/x.png" (optional)
///   frames.txt                 "timestamp source seq kind check t_err_m r_err_deg coverage rgb_file"
///                              with kind = synthetic | real (the per-frame source flag)
///
/// Crash safety: each image is encoded in memory, written to a hidden temporary file in the same
/// folder and renamed into place; only then are the index lines appended, each with one write(2)
/// on an O_APPEND descriptor. So after a crash at any instant (even SIGKILL) every file an index
/// lists exists and is complete, and no index holds a partial line. Lines are appended in receipt
/// order; Close() rewrites the index files sorted by timestamp (atomically, temp + rename), which
/// interleaves synthetic and real frames by time.
///
/// Thread-compatible: one thread calls Write/Flush/Close.
class TumSequenceWriter {
 public:
  /// Creates the folders and opens the index files. Throws std::runtime_error naming the path
  /// when a folder cannot be created or a file cannot be opened, or when out_dir already holds
  /// a sequence and options.append is false.
  explicit TumSequenceWriter(TumSequenceWriterOptions options);
  ~TumSequenceWriter();
  TumSequenceWriter(const TumSequenceWriter&) = delete;
  TumSequenceWriter& operator=(const TumSequenceWriter&) = delete;

  /// Writes the frame's images and appends its index lines. Precondition: rgb CV_8UC3 and depth
  /// CV_32FC1 of the same non-zero size, finite stamp (std::invalid_argument otherwise). Throws
  /// std::runtime_error naming the file on an I/O error. When it returns, the frame is on disk.
  WrittenFiles Write(const SinkFrame& frame, const FrameRecord& record = {});

  /// Flushes the index files to the OS (and fsyncs them). Cheap; safe to call often.
  void Flush();
  /// Flush, then rewrite every index file sorted by timestamp. Idempotent; the destructor calls
  /// it (swallowing errors), so call it explicitly to see them.
  void Close();

  size_t frames_written() const { return frames_written_; }
  /// Depth pixels that could not be represented (beyond 65535 / depth_scale m): written as 0.
  size_t depth_pixels_out_of_range() const { return depth_out_of_range_; }
  const std::string& out_dir() const { return options_.out_dir; }

  /// Metres (CV_32FC1, 0 = invalid) to TUM units (CV_16UC1, rounded); non-finite, non-positive
  /// and out-of-range values become 0 and out-of-range ones are counted in *out_of_range.
  static cv::Mat DepthToUnits(const cv::Mat& depth_m, double scale, size_t* out_of_range);
  /// TUM units (CV_16UC1) to metres (CV_32FC1), 0 stays 0.
  static cv::Mat DepthFromUnits(const cv::Mat& depth_units, double scale);

 private:
  struct IndexFile {
    std::string name;  // relative to out_dir
    int fd = -1;
  };
  void OpenIndex(IndexFile* index, const std::string& header);
  void AppendLine(IndexFile* index, const std::string& line);
  std::string UniqueBaseName(double stamp, bool synthetic);
  void WriteFileAtomic(const std::string& relative_path, const std::vector<unsigned char>& bytes);
  void SortIndex(const IndexFile& index);

  TumSequenceWriterOptions options_;
  IndexFile rgb_index_{"rgb.txt"};
  IndexFile depth_index_{"depth.txt"};
  IndexFile groundtruth_index_{"groundtruth.txt"};
  IndexFile associations_index_{"associations.txt"};
  IndexFile frames_index_{"frames.txt"};
  std::set<std::string> used_names_;
  size_t frames_written_ = 0;
  size_t depth_out_of_range_ = 0;
  bool closed_ = false;
};

}  // namespace p2i::slam_sink
