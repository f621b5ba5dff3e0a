/// @file msg_convert.h
/// @brief Conversions between scene types (Pose, CameraInfo, RgbdSample) and p2i messages,
/// header-only so that the camera and pose_source nodes share them.
#pragma once

#include <cstring>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "msgs/codec.h"
#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"

namespace p2i::nodes {

inline void ToMsg(const scene::Pose& pose, msgs::pb::Pose* out,
                  const std::string& parent_frame = "world",
                  const std::string& child_frame = "camera") {
  const scene::Vector7d v = pose.ToVector7();
  msgs::SetPose({v(0), v(1), v(2), v(3), v(4), v(5), v(6)}, out);
  out->set_parent_frame(parent_frame);
  out->set_child_frame(child_frame);
}

/// The pose of a decoded (hence validated) message.
inline scene::Pose FromMsg(const msgs::pb::Pose& pose) {
  const auto v = msgs::PoseVector(pose);
  scene::Vector7d x;
  for (int i = 0; i < 7; ++i) x(i) = v[i];
  return scene::Pose::FromVector7(x);
}

inline void ToMsg(const scene::CameraInfo& c, msgs::pb::CameraInfo* out) {
  out->set_width(static_cast<uint32_t>(c.image_width));
  out->set_height(static_cast<uint32_t>(c.image_height));
  out->set_distortion_model(c.distortion_model);
  out->set_camera_name(c.camera_name);
  out->clear_d();
  out->clear_k();
  out->clear_r();
  out->clear_p();
  for (double d : c.distortion_coefficients) out->add_d(d);
  for (double k : c.camera_matrix) out->add_k(k);
  for (double r : c.rectification_matrix) out->add_r(r);
  for (double p : c.projection_matrix) out->add_p(p);
}

inline scene::CameraInfo FromMsg(const msgs::pb::CameraInfo& m) {
  scene::CameraInfo c;
  c.image_width = static_cast<int>(m.width());
  c.image_height = static_cast<int>(m.height());
  c.distortion_model = m.distortion_model();
  c.camera_name = m.camera_name();
  c.distortion_coefficients.assign(m.d().begin(), m.d().end());
  for (int i = 0; i < 9 && i < m.k_size(); ++i) c.camera_matrix[i] = m.k(i);
  for (int i = 0; i < 9 && i < m.r_size(); ++i) c.rectification_matrix[i] = m.r(i);
  for (int i = 0; i < 12 && i < m.p_size(); ++i) c.projection_matrix[i] = m.p(i);
  return c;
}

/// Copies a CV_8UC3 (RGB order) or CV_32FC1 (metres) matrix into a packed message image.
inline msgs::Image ToImage(const cv::Mat& m) {
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

/// A view of a message image as a cv::Mat (no copy; valid while `img` lives). RGB8 -> CV_8UC3,
/// DEPTH32F -> CV_32FC1, DEPTH16U -> CV_16UC1 (raw units).
inline cv::Mat ToMat(const msgs::Image& img) {
  int type = -1;
  switch (img.encoding) {
    case msgs::pb::RGB8: type = CV_8UC3; break;
    case msgs::pb::DEPTH32F: type = CV_32FC1; break;
    case msgs::pb::DEPTH16U: type = CV_16UC1; break;
    case msgs::pb::MONO8: type = CV_8UC1; break;
    case msgs::pb::MONO16: type = CV_16UC1; break;
    default: throw std::invalid_argument("ToMat: unsupported encoding");
  }
  return cv::Mat(static_cast<int>(img.height), static_cast<int>(img.width), type,
                 const_cast<uint8_t*>(img.data->data()),
                 img.step == 0 ? static_cast<size_t>(cv::Mat::AUTO_STEP) : img.step);
}

}  // namespace p2i::nodes
