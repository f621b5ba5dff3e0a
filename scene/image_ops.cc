/// @file image_ops.cc
/// @brief Resize / centre-crop of RGB-D samples.
#include "scene/image_ops.h"

#include <stdexcept>

#include <opencv2/imgproc.hpp>

namespace p2i::scene {
namespace {

void CheckSize(int w, int h, const char* where) {
  if (w <= 0 || h <= 0) {
    throw std::invalid_argument(std::string(where) + ": output size " + std::to_string(w) + "x" +
                                std::to_string(h) + " must be positive");
  }
}

}  // namespace

cv::Rect CenterCropRect(int width, int height, int out_width, int out_height) {
  CheckSize(width, height, "CenterCropRect");
  CheckSize(out_width, out_height, "CenterCropRect");
  // Compare aspect ratios in integers: width/height vs out_width/out_height.
  const long long lhs = static_cast<long long>(width) * out_height;
  const long long rhs = static_cast<long long>(out_width) * height;
  int cw = width, ch = height;
  if (lhs > rhs) {
    cw = static_cast<int>((static_cast<long long>(height) * out_width + out_height / 2) /
                          out_height);
  } else if (lhs < rhs) {
    ch = static_cast<int>((static_cast<long long>(width) * out_height + out_width / 2) /
                          out_width);
  }
  return cv::Rect((width - cw) / 2, (height - ch) / 2, cw, ch);
}

RgbdSample ResizeSample(const RgbdSample& sample, int out_width, int out_height) {
  CheckSize(out_width, out_height, "ResizeSample");
  RgbdSample out;
  out.stamp = sample.stamp;
  out.pose = sample.pose;
  out.id = sample.id;
  const cv::Size size(out_width, out_height);
  if (!sample.rgb.empty()) {
    const bool shrink = out_width < sample.rgb.cols || out_height < sample.rgb.rows;
    cv::resize(sample.rgb, out.rgb, size, 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  if (!sample.depth.empty()) {
    // INTER_NEAREST_EXACT, not INTER_NEAREST: OpenCV's INTER_NEAREST takes source pixel
    // floor(x * scale), which is not the pixel under the output pixel's centre (that is
    // floor((x + 0.5) * scale)): shrinking 480 -> 128 shifted the depth 0.37 output pixels up and
    // left of the colour (INTER_AREA/INTER_LINEAR are centre-aligned) and of the calibration.
    cv::resize(sample.depth, out.depth, size, 0, 0, cv::INTER_NEAREST_EXACT);
  }
  return out;
}

RgbdSample CenterCropResizeSample(const RgbdSample& sample, int out_width, int out_height) {
  const cv::Mat& ref = sample.rgb.empty() ? sample.depth : sample.rgb;
  if (ref.empty()) throw std::invalid_argument("CenterCropResizeSample: empty sample");
  if (!sample.rgb.empty() && !sample.depth.empty() && sample.rgb.size() != sample.depth.size()) {
    throw std::invalid_argument("CenterCropResizeSample: rgb and depth sizes differ in '" +
                                sample.id + "'");
  }
  const cv::Rect crop = CenterCropRect(ref.cols, ref.rows, out_width, out_height);
  RgbdSample cropped = sample;
  if (!sample.rgb.empty()) cropped.rgb = sample.rgb(crop);
  if (!sample.depth.empty()) cropped.depth = sample.depth(crop);
  return ResizeSample(cropped, out_width, out_height);
}

CameraInfo CenterCropResizeCamera(const CameraInfo& camera, int out_width, int out_height) {
  const cv::Rect crop =
      CenterCropRect(camera.image_width, camera.image_height, out_width, out_height);
  return camera.Cropped(crop.x, crop.y, crop.width, crop.height).Scaled(out_width, out_height);
}

RgbdDataset CenterCropResizeDataset(const RgbdDataset& dataset, int out_width, int out_height) {
  RgbdDataset out;
  out.camera = CenterCropResizeCamera(dataset.camera, out_width, out_height);
  out.frames.reserve(dataset.frames.size());
  for (const RgbdSample& s : dataset.frames) {
    out.frames.push_back(CenterCropResizeSample(s, out_width, out_height));
  }
  return out;
}

}  // namespace p2i::scene
