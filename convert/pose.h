/// @file pose.h
/// @brief pb::Pose <-> scene::Pose, and plain-double access to pose messages (TUM order).
#pragma once

#include <array>
#include <string>

#include "msgs/p2i.pb.h"
#include "scene/pose.h"

namespace p2i::convert {

/// Writes a 7-vector in TUM order (tx ty tz qx qy qz qw) into a pose message (frames untouched).
void SetPose(const std::array<double, 7>& txyz_qxyzw, msgs::pb::Pose* pose);
/// The 7-vector (TUM order) of a pose message, as sent (no validation).
std::array<double, 7> PoseVector(const msgs::pb::Pose& pose);

/// Fills a pose message from a scene pose (camera-to-world) and names its frames.
void ToMsg(const scene::Pose& pose, msgs::pb::Pose* out, const std::string& parent_frame = "world",
           const std::string& child_frame = "camera");
/// The scene pose of a decoded (hence validated: finite, unit quaternion) pose message.
scene::Pose FromMsg(const msgs::pb::Pose& pose);

}  // namespace p2i::convert
