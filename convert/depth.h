/// @file depth.h
/// @brief The one decoder of depth message images to metres (the rule of msgs/p2i.proto).
#pragma once

#include <opencv2/core.hpp>

#include "msgs/image.h"

namespace p2i::convert {

/// Depth in metres of a DEPTH16U or DEPTH32F message image, as an owned CV_32FC1 matrix.
/// Follows p2i.proto for both encodings: metres = value x depth_scale; a pixel whose raw value
/// equals `invalid_value`, is not finite, or gives metres that are not finite and positive
/// becomes 0 (the project's "no depth"). Throws std::invalid_argument naming the encoding for
/// any other encoding, or for an image without data.
cv::Mat DepthToMetres(const msgs::Image& img);

}  // namespace p2i::convert
