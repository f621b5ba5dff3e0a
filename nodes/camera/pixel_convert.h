/// @file pixel_convert.h
/// @brief Camera pixel formats (GenICam names) to RGB8 images and Mono16 to metric depth;
/// independent of any camera library so that it is unit-tested in every build.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace p2i::nodes {

/// The pixel formats the live backends convert (GenICam PFNC names).
enum class PixelFormat {
  kMono8, kMono16, kRGB8, kBGR8, kBayerRG8, kBayerGR8, kBayerGB8, kBayerBG8
};

/// "Mono8" -> kMono8 ... (exact GenICam spelling); nullopt for any other name.
std::optional<PixelFormat> ParsePixelFormat(const std::string& name);
const char* ToString(PixelFormat format);
/// "Mono8, Mono16, RGB8, BGR8, BayerRG8, BayerGR8, BayerGB8, BayerBG8".
std::string SupportedPixelFormats();
int BytesPerPixel(PixelFormat format);

/// Converts one packed image (rows of width * BytesPerPixel, `stride` bytes apart; 0 = packed)
/// to CV_8UC3 RGB: Mono8 -> grey, Mono16 -> grey (value / 257, little-endian), RGB8/BGR8 ->
/// RGB, Bayer (the colour of the top-left 2x2 cell named by the format, e.g. BayerRG8 = R G /
/// G B) -> bilinear demosaic. Throws std::invalid_argument when `size` is too small.
cv::Mat ToRgb8(const uint8_t* data, size_t size, int width, int height, PixelFormat format,
               size_t stride = 0);

/// Mono16 (little-endian) depth to CV_32FC1 metres: value * scale; 0 stays 0 (invalid).
cv::Mat Mono16ToDepth(const uint8_t* data, size_t size, int width, int height, double scale,
                      size_t stride = 0);

}  // namespace p2i::nodes
