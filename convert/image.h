/// @file image.h
/// @brief msgs::Image <-> cv::Mat: packing a matrix into a message image, viewing a message
/// image as a matrix, and an owned RGB copy. Depth in metres is convert/depth.h.
#pragma once

#include <opencv2/core.hpp>

#include "msgs/image.h"

namespace p2i::convert {

/// Copies a CV_8UC3 (RGB order) or CV_32FC1 (metres; sent with depth_scale 1, invalid value 0)
/// matrix into a packed message image. Throws std::invalid_argument for other types.
msgs::Image ToImage(const cv::Mat& m);

/// A view of a message image as a cv::Mat (no copy; valid while `img` lives): RGB8 -> CV_8UC3,
/// DEPTH32F -> CV_32FC1, DEPTH16U -> CV_16UC1 (raw units, not metres), MONO8 -> CV_8UC1,
/// MONO16 -> CV_16UC1. Throws std::invalid_argument for an unknown encoding or no data.
cv::Mat ToMat(const msgs::Image& img);

/// An owned CV_8UC3 copy (RGB order) of an RGB8 message image. Throws std::invalid_argument
/// naming the encoding for any other, or for an image without data.
cv::Mat RgbToMat(const msgs::Image& img);

}  // namespace p2i::convert
