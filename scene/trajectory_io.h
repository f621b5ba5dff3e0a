/// @file trajectory_io.h
/// @brief TUM trajectory files: "timestamp tx ty tz qx qy qz qw" per line, camera-to-world.
#pragma once

#include <string>
#include <vector>

#include "scene/pose.h"

namespace p2i::scene {

/// Reads a TUM trajectory. Lines starting with '#' and blank lines are skipped. Throws
/// std::runtime_error "FILE:LINE: what" on a malformed line, non-finite values, or timestamps
/// that are not strictly increasing; "FILE: cannot open" when the file cannot be read.
std::vector<StampedPose> ReadTumTrajectory(const std::string& path);
/// Same from text; `source` names it in error messages.
std::vector<StampedPose> ParseTumTrajectory(const std::string& text,
                                            const std::string& source = "<string>");

/// The file text: an optional '#' comment line, a format comment line, then one pose per line.
std::string FormatTumTrajectory(const std::vector<StampedPose>& trajectory,
                                const std::string& comment = "");
/// Writes atomically (temporary file + rename). Throws std::runtime_error naming the path.
void WriteTumTrajectory(const std::string& path, const std::vector<StampedPose>& trajectory,
                        const std::string& comment = "");

}  // namespace p2i::scene
