/// @file image.cc
/// @brief Message image <-> cv::Mat.
#include "convert/image.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace p2i::convert {

msgs::Image ToImage(const cv::Mat& m) {
  msgs::Image img;
  if (m.type() == CV_8UC3) {
    img = msgs::Image::Allocate(msgs::pb::RGB8, m.cols, m.rows);
  } else if (m.type() == CV_32FC1) {
    img = msgs::Image::Allocate(msgs::pb::DEPTH32F, m.cols, m.rows);
    img.depth_scale = 1.0;
    img.invalid_value = 0.0;
  } else {
    throw std::invalid_argument("ToImage: only CV_8UC3 (RGB) and CV_32FC1 (depth) are sent");
  }
  const size_t row = m.cols * m.elemSize();
  for (int r = 0; r < m.rows; ++r) std::memcpy(img.MutableData() + r * row, m.ptr(r), row);
  return img;
}

cv::Mat ToMat(const msgs::Image& img) {
  int type = -1;
  switch (img.encoding) {
    case msgs::pb::RGB8: type = CV_8UC3; break;
    case msgs::pb::DEPTH32F: type = CV_32FC1; break;
    case msgs::pb::DEPTH16U: type = CV_16UC1; break;
    case msgs::pb::MONO8: type = CV_8UC1; break;
    case msgs::pb::MONO16: type = CV_16UC1; break;
    default:
      throw std::invalid_argument(std::string("ToMat: unsupported encoding ") +
                                  msgs::EncodingName(img.encoding));
  }
  if (!img.data) throw std::invalid_argument("ToMat: the image has no data");
  return cv::Mat(static_cast<int>(img.height), static_cast<int>(img.width), type,
                 const_cast<uint8_t*>(img.data->data()),
                 img.step == 0 ? static_cast<size_t>(cv::Mat::AUTO_STEP) : img.step);
}

cv::Mat RgbToMat(const msgs::Image& img) {
  if (img.encoding != msgs::pb::RGB8) {
    throw std::invalid_argument(std::string("colour image must be RGB8, got ") +
                                msgs::EncodingName(img.encoding));
  }
  if (!img.data || img.width == 0 || img.height == 0) {
    throw std::invalid_argument("colour image has no data");
  }
  return ToMat(img).clone();
}

}  // namespace p2i::convert
