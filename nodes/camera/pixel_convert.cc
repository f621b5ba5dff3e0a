/// @file pixel_convert.cc
#include "nodes/camera/pixel_convert.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace p2i::nodes {
namespace {

struct FormatName {
  PixelFormat format;
  const char* name;
};
constexpr FormatName kFormats[] = {
    {PixelFormat::kMono8, "Mono8"},         {PixelFormat::kMono16, "Mono16"},
    {PixelFormat::kRGB8, "RGB8"},           {PixelFormat::kBGR8, "BGR8"},
    {PixelFormat::kBayerRG8, "BayerRG8"},   {PixelFormat::kBayerGR8, "BayerGR8"},
    {PixelFormat::kBayerGB8, "BayerGB8"},   {PixelFormat::kBayerBG8, "BayerBG8"},
};

/// A view of the caller's bytes (no copy), checked for size.
cv::Mat View(const uint8_t* data, size_t size, int width, int height, int type, int bpp,
             size_t stride) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("image size must be > 0");
  const size_t row = static_cast<size_t>(width) * bpp;
  if (stride == 0) stride = row;
  if (stride < row || size < stride * (height - 1) + row) {
    throw std::invalid_argument("image buffer of " + std::to_string(size) +
                                " bytes is too small for " + std::to_string(width) + "x" +
                                std::to_string(height) + " at " + std::to_string(bpp) +
                                " bytes per pixel");
  }
  return cv::Mat(height, width, type, const_cast<uint8_t*>(data), stride);
}

}  // namespace

std::optional<PixelFormat> ParsePixelFormat(const std::string& name) {
  for (const FormatName& f : kFormats) {
    if (name == f.name) return f.format;
  }
  return std::nullopt;
}

const char* ToString(PixelFormat format) {
  for (const FormatName& f : kFormats) {
    if (format == f.format) return f.name;
  }
  return "?";
}

std::string SupportedPixelFormats() {
  std::string out;
  for (const FormatName& f : kFormats) out += (out.empty() ? "" : ", ") + std::string(f.name);
  return out;
}

int BytesPerPixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono16: return 2;
    case PixelFormat::kRGB8:
    case PixelFormat::kBGR8: return 3;
    default: return 1;
  }
}

cv::Mat ToRgb8(const uint8_t* data, size_t size, int width, int height, PixelFormat format,
               size_t stride) {
  const int bpp = BytesPerPixel(format);
  const int type = bpp == 3 ? CV_8UC3 : (bpp == 2 ? CV_16UC1 : CV_8UC1);
  const cv::Mat in = View(data, size, width, height, type, bpp, stride);
  cv::Mat out;
  switch (format) {
    case PixelFormat::kMono8: cv::cvtColor(in, out, cv::COLOR_GRAY2RGB); break;
    case PixelFormat::kMono16: {
      cv::Mat grey;
      in.convertTo(grey, CV_8U, 1.0 / 257.0);
      cv::cvtColor(grey, out, cv::COLOR_GRAY2RGB);
      break;
    }
    case PixelFormat::kRGB8: out = in.clone(); break;
    case PixelFormat::kBGR8: cv::cvtColor(in, out, cv::COLOR_BGR2RGB); break;
    // OpenCV names a Bayer pattern by the 2nd and 3rd pixel of its 2nd row, GenICam by the
    // top-left 2x2 cell: GenICam RGGB ("BayerRG") is OpenCV's "BayerBG", and so on.
    case PixelFormat::kBayerRG8: cv::cvtColor(in, out, cv::COLOR_BayerBG2RGB); break;
    case PixelFormat::kBayerGR8: cv::cvtColor(in, out, cv::COLOR_BayerGB2RGB); break;
    case PixelFormat::kBayerGB8: cv::cvtColor(in, out, cv::COLOR_BayerGR2RGB); break;
    case PixelFormat::kBayerBG8: cv::cvtColor(in, out, cv::COLOR_BayerRG2RGB); break;
  }
  return out;
}

cv::Mat Mono16ToDepth(const uint8_t* data, size_t size, int width, int height, double scale,
                      size_t stride) {
  const cv::Mat in = View(data, size, width, height, CV_16UC1, 2, stride);
  cv::Mat out;
  in.convertTo(out, CV_32F, scale);
  return out;
}

}  // namespace p2i::nodes
