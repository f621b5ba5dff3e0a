/// @file message_conversion.h
/// @brief Decoded p2i messages (View, RgbdFrame, CameraInfo) to the sink's types.
#pragma once

#include <string>

#include "msgs/codec.h"
#include "nodes/slam_sink/sink_frame.h"
#include "scene/camera_info.h"

namespace p2i::slam_sink {

/// The sink frame of a synthetic view. stamp = header.capture_stamp_ns (publish stamp if 0);
/// source = "<publisher>@<topic>" (the key of sequence accounting). Images: convert::RgbToMat and
/// convert::DepthToMetres (metres, invalid -> 0); throws like them.
SinkFrame FrameFromView(const msgs::View& view, const std::string& topic);
/// The sink frame of a real camera frame (has_pose from the message).
SinkFrame FrameFromRgbd(const msgs::RgbdFrame& frame, const std::string& topic);

/// The calibration carried by a CameraInfo message (convert::FromMsg), named "camera" when the
/// message names none.
scene::CameraInfo CameraFromMsg(const msgs::pb::CameraInfo& msg);

}  // namespace p2i::slam_sink
