/// @file camera_info.h
/// @brief pb::CameraInfo <-> scene::CameraInfo (ROS camera_info fields, copied as they are).
#pragma once

#include "msgs/p2i.pb.h"
#include "scene/camera_info.h"

namespace p2i::convert {

/// Fills a CameraInfo message (size, distortion model and coefficients, K, R, P, name).
void ToMsg(const scene::CameraInfo& camera, msgs::pb::CameraInfo* out);
/// The calibration of a CameraInfo message; K, R and P entries the message lacks keep the
/// scene::CameraInfo defaults.
scene::CameraInfo FromMsg(const msgs::pb::CameraInfo& msg);

}  // namespace p2i::convert
