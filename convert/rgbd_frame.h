/// @file rgbd_frame.h
/// @brief A decoded RgbdFrame message as a scene::RgbdSample (owned images, depth in metres).
#pragma once

#include "msgs/image.h"
#include "scene/rgbd_sample.h"

namespace p2i::convert {

/// stamp = header.capture_stamp_ns in seconds, id = header.seq, pose from the message when it
/// has one (identity otherwise: check meta.has_pose()), rgb = RgbToMat, depth = DepthToMetres.
/// Throws std::invalid_argument like those two.
scene::RgbdSample ToSample(const msgs::RgbdFrame& frame);

}  // namespace p2i::convert
