/// @file message_conversion.cc
/// @brief Message -> sink type conversions.
#include "nodes/slam_sink/message_conversion.h"

#include <cmath>
#include <stdexcept>

#include "nodes/camera/msg_convert.h"

namespace p2i::slam_sink {
namespace {

scene::Pose PoseFromMsg(const msgs::pb::Pose& pose) { return nodes::FromMsg(pose); }

double StampOf(const msgs::pb::Header& h) {
  const int64_t ns = h.capture_stamp_ns() != 0 ? h.capture_stamp_ns() : h.publish_stamp_ns();
  return static_cast<double>(ns) * 1e-9;
}

std::string SourceOf(const msgs::pb::Header& h, const std::string& topic) {
  return (h.publisher().empty() ? std::string("?") : h.publisher()) + "@" + topic;
}

}  // namespace

cv::Mat ImageToMat(const msgs::Image& image, bool depth) {
  if (!image.data || image.width == 0 || image.height == 0) {
    throw std::invalid_argument("ImageToMat: the image has no data");
  }
  const int rows = static_cast<int>(image.height), cols = static_cast<int>(image.width);
  if (!depth) {
    if (image.encoding != msgs::pb::RGB8) {
      throw std::invalid_argument(std::string("ImageToMat: colour must be RGB8, got ") +
                                  msgs::EncodingName(image.encoding));
    }
    return nodes::ToMat(image).clone();
  }
  if (image.encoding != msgs::pb::DEPTH32F && image.encoding != msgs::pb::DEPTH16U) {
    throw std::invalid_argument(std::string("ImageToMat: depth must be DEPTH32F or DEPTH16U, got ") +
                                msgs::EncodingName(image.encoding));
  }
  const cv::Mat raw = nodes::ToMat(image);  // a view: CV_32FC1 or CV_16UC1, raw units
  cv::Mat metres(rows, cols, CV_32FC1);
  for (int r = 0; r < rows; ++r) {
    float* out = metres.ptr<float>(r);
    for (int c = 0; c < cols; ++c) {
      const double v = raw.type() == CV_32FC1 ? raw.at<float>(r, c) : raw.at<uint16_t>(r, c);
      const double m = v * image.depth_scale;
      out[c] = (!std::isfinite(v) || v == image.invalid_value || !std::isfinite(m) || m <= 0.0)
                   ? 0.0f
                   : static_cast<float>(m);
    }
  }
  return metres;
}

SinkFrame FrameFromView(const msgs::View& view, const std::string& topic) {
  SinkFrame frame;
  const msgs::pb::Header& h = view.meta.header();
  frame.stamp = StampOf(h);
  frame.pose = PoseFromMsg(view.meta.pose());
  frame.has_pose = true;
  frame.rgb = ImageToMat(view.rgb, false);
  frame.depth = ImageToMat(view.depth, true);
  frame.synthetic = true;
  frame.source = SourceOf(h, topic);
  frame.seq = h.seq();
  frame.publish_stamp_ns = h.publish_stamp_ns();
  frame.coverage = view.meta.coverage();
  frame.method = view.meta.method();
  frame.model_version = static_cast<int64_t>(view.meta.model_version());
  return frame;
}

SinkFrame FrameFromRgbd(const msgs::RgbdFrame& msg, const std::string& topic) {
  SinkFrame frame;
  const msgs::pb::Header& h = msg.meta.header();
  frame.stamp = StampOf(h);
  frame.has_pose = msg.meta.has_pose();
  if (frame.has_pose) frame.pose = PoseFromMsg(msg.meta.pose());
  frame.rgb = ImageToMat(msg.rgb, false);
  frame.depth = ImageToMat(msg.depth, true);
  frame.synthetic = false;
  frame.source = SourceOf(h, topic);
  frame.seq = h.seq();
  frame.publish_stamp_ns = h.publish_stamp_ns();
  return frame;
}

scene::CameraInfo CameraFromMsg(const msgs::pb::CameraInfo& m) {
  scene::CameraInfo c = nodes::FromMsg(m);
  if (c.camera_name.empty()) c.camera_name = "camera";
  return c;
}

}  // namespace p2i::slam_sink
