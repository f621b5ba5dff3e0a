/// @file message_conversion.cc
/// @brief Message -> sink type conversions.
#include "nodes/slam_sink/message_conversion.h"

#include "convert/camera_info.h"
#include "convert/depth.h"
#include "convert/image.h"
#include "convert/pose.h"

namespace p2i::slam_sink {
namespace {

double StampOf(const msgs::pb::Header& h) {
  const int64_t ns = h.capture_stamp_ns() != 0 ? h.capture_stamp_ns() : h.publish_stamp_ns();
  return static_cast<double>(ns) * 1e-9;
}

std::string SourceOf(const msgs::pb::Header& h, const std::string& topic) {
  return (h.publisher().empty() ? std::string("?") : h.publisher()) + "@" + topic;
}

}  // namespace

SinkFrame FrameFromView(const msgs::View& view, const std::string& topic) {
  SinkFrame frame;
  const msgs::pb::Header& h = view.meta.header();
  frame.stamp = StampOf(h);
  frame.pose = convert::FromMsg(view.meta.pose());
  frame.has_pose = true;
  frame.rgb = convert::RgbToMat(view.rgb);
  frame.depth = convert::DepthToMetres(view.depth);
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
  if (frame.has_pose) frame.pose = convert::FromMsg(msg.meta.pose());
  frame.rgb = convert::RgbToMat(msg.rgb);
  frame.depth = convert::DepthToMetres(msg.depth);
  frame.synthetic = false;
  frame.source = SourceOf(h, topic);
  frame.seq = h.seq();
  frame.publish_stamp_ns = h.publish_stamp_ns();
  return frame;
}

scene::CameraInfo CameraFromMsg(const msgs::pb::CameraInfo& m) {
  scene::CameraInfo c = convert::FromMsg(m);
  if (c.camera_name.empty()) c.camera_name = "camera";
  return c;
}

}  // namespace p2i::slam_sink
