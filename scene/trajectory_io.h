/// @file trajectory_io.h
/// @brief TUM trajectory files: "timestamp tx ty tz qx qy qz qw" per line, camera-to-world.
#pragma once

#include <string>
#include <vector>

#include "scene/pose.h"

namespace p2i::scene {

/// What to do with timestamps that are not strictly increasing.
enum class TumStampOrder {
  kStrict,  ///< error naming the line (trajectories p2i writes and reads back)
  kSort,    ///< stable-sort by stamp (recorded ground truth, e.g. TUM RGB-D groundtruth.txt,
            ///< is not always sorted)
};

/// Reads a TUM trajectory. Lines starting with '#' and blank lines are skipped. Throws
/// std::runtime_error "FILE:LINE: what" on a malformed line, non-finite values, or (kStrict)
/// timestamps that are not strictly increasing; "FILE: cannot open" when the file cannot be read.
std::vector<StampedPose> ReadTumTrajectory(const std::string& path,
                                           TumStampOrder order = TumStampOrder::kStrict);
/// Same from text; `source` names it in error messages.
std::vector<StampedPose> ParseTumTrajectory(const std::string& text,
                                            const std::string& source = "<string>",
                                            TumStampOrder order = TumStampOrder::kStrict);

/// The file text: an optional '#' comment line, a format comment line, then one pose per line.
std::string FormatTumTrajectory(const std::vector<StampedPose>& trajectory,
                                const std::string& comment = "");
/// Writes atomically (temporary file + rename). Throws std::runtime_error naming the path.
void WriteTumTrajectory(const std::string& path, const std::vector<StampedPose>& trajectory,
                        const std::string& comment = "");

}  // namespace p2i::scene
