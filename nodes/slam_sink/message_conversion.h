/// @file message_conversion.h
/// @brief Decoded p2i messages (View, RgbdFrame, CameraInfo) to the sink's types.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "msgs/codec.h"
#include "nodes/slam_sink/sink_frame.h"
#include "scene/camera_info.h"

namespace p2i::slam_sink {

/// A message image as an owned cv::Mat: RGB8 -> CV_8UC3 (RGB order); DEPTH32F / DEPTH16U ->
/// CV_32FC1 metres (value * depth_scale, `invalid_value` and non-finite -> 0). Throws
/// std::invalid_argument for other encodings or an image without data.
cv::Mat ImageToMat(const msgs::Image& image, bool depth);

/// The sink frame of a synthetic view. stamp = header.capture_stamp_ns (publish stamp if 0);
/// source = "<publisher>@<topic>" (the key of sequence accounting). Throws like ImageToMat.
SinkFrame FrameFromView(const msgs::View& view, const std::string& topic);
/// The sink frame of a real camera frame (has_pose from the message).
SinkFrame FrameFromRgbd(const msgs::RgbdFrame& frame, const std::string& topic);

/// The calibration carried by a CameraInfo message.
scene::CameraInfo CameraFromMsg(const msgs::pb::CameraInfo& msg);

}  // namespace p2i::slam_sink
