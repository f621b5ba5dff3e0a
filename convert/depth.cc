/// @file depth.cc
/// @brief Depth message images to metres.
#include "convert/depth.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "convert/image.h"

namespace p2i::convert {
namespace {

template <class T>
void Decode(const cv::Mat& raw, double scale, double invalid, cv::Mat* metres) {
  for (int r = 0; r < raw.rows; ++r) {
    const T* in = raw.ptr<T>(r);
    float* out = metres->ptr<float>(r);
    for (int c = 0; c < raw.cols; ++c) {
      const double v = static_cast<double>(in[c]);
      const double m = v * scale;
      out[c] = (!std::isfinite(v) || v == invalid || !std::isfinite(m) || m <= 0.0)
                   ? 0.0f
                   : static_cast<float>(m);
    }
  }
}

}  // namespace

cv::Mat DepthToMetres(const msgs::Image& img) {
  if (img.encoding != msgs::pb::DEPTH32F && img.encoding != msgs::pb::DEPTH16U) {
    throw std::invalid_argument(std::string("depth image must be DEPTH32F or DEPTH16U, got ") +
                                msgs::EncodingName(img.encoding));
  }
  if (!img.data || img.width == 0 || img.height == 0) {
    throw std::invalid_argument("depth image has no data");
  }
  const cv::Mat raw = ToMat(img);  // a view in raw units
  cv::Mat metres(raw.rows, raw.cols, CV_32FC1);
  if (img.encoding == msgs::pb::DEPTH32F) {
    Decode<float>(raw, img.depth_scale, img.invalid_value, &metres);
  } else {
    Decode<uint16_t>(raw, img.depth_scale, img.invalid_value, &metres);
  }
  return metres;
}

}  // namespace p2i::convert
