/// @file foxglove_convert.cc
/// @brief RgbdFrame / View / CameraInfo / PoseStamped / PoseRequest -> foxglove.* messages.
#include "recording/foxglove_convert.h"

#include <cmath>
#include <cstring>

#include "convert/depth.h"
#include "msgs/codec.h"
#include "msgs/foxglove.pb.h"

namespace p2i::recording {

namespace {

namespace pb = msgs::pb;

void SetStamp(int64_t ns, google::protobuf::Timestamp* t) {
  t->set_seconds(ns / 1000000000);
  t->set_nanos(static_cast<int32_t>(ns % 1000000000));
}

std::string FrameOf(const pb::Header& h, const pb::Pose* pose) {
  if (pose && !pose->child_frame().empty()) return pose->child_frame();
  if (!h.frame_id().empty()) return h.frame_id();
  return "camera";
}

std::string ParentOf(const pb::Pose& pose) {
  return pose.parent_frame().empty() ? "world" : pose.parent_frame();
}

void ToFoxglovePose(const pb::Pose& p, foxglove::Pose* out) {
  out->mutable_position()->set_x(p.position().x());
  out->mutable_position()->set_y(p.position().y());
  out->mutable_position()->set_z(p.position().z());
  out->mutable_orientation()->set_x(p.orientation().x());
  out->mutable_orientation()->set_y(p.orientation().y());
  out->mutable_orientation()->set_z(p.orientation().z());
  out->mutable_orientation()->set_w(p.orientation().w());
}

template <typename M>
void Add(const std::string& topic, const M& m, std::vector<FoxgloveMessage>* out) {
  out->push_back({topic, M::descriptor(), m.SerializeAsString()});
}

void AddRgb(const std::string& topic, int64_t stamp, const std::string& frame,
            const msgs::Image& img, std::vector<FoxgloveMessage>* out) {
  foxglove::RawImage r;
  SetStamp(stamp, r.mutable_timestamp());
  r.set_frame_id(frame);
  r.set_width(img.width);
  r.set_height(img.height);
  r.set_encoding("rgb8");
  r.set_step(img.step);
  r.set_data(img.data->data(), img.data->size());
  Add(topic + "/foxglove/rgb", r, out);
}

/// Depth as 16UC1 millimetres (Foxglove colour-maps 16UC1; 32FC1 would be read as brightness).
void AddDepth(const std::string& topic, int64_t stamp, const std::string& frame,
              const msgs::Image& img, std::vector<FoxgloveMessage>* out) {
  foxglove::RawImage r;
  SetStamp(stamp, r.mutable_timestamp());
  r.set_frame_id(frame);
  r.set_width(img.width);
  r.set_height(img.height);
  r.set_encoding("16UC1");
  r.set_step(img.width * 2);
  // Metres by the project's one depth decoder (value x depth_scale, invalid / non-finite -> 0).
  const cv::Mat metres = convert::DepthToMetres(img);
  std::string px(static_cast<size_t>(img.width) * img.height * 2, '\0');
  auto* dst = reinterpret_cast<uint16_t*>(px.data());
  for (uint32_t y = 0; y < img.height; ++y) {
    const float* row = metres.ptr<float>(static_cast<int>(y));
    for (uint32_t x = 0; x < img.width; ++x) {
      dst[static_cast<size_t>(y) * img.width + x] =
          static_cast<uint16_t>(std::clamp(std::lround(row[x] * 1000.0), 0l, 65535l));
    }
  }
  r.set_data(std::move(px));
  Add(topic + "/foxglove/depth", r, out);
}

void AddCalibration(const std::string& topic, int64_t stamp, const std::string& frame,
                    const pb::CameraInfo& c, std::vector<FoxgloveMessage>* out) {
  foxglove::CameraCalibration k;
  SetStamp(stamp, k.mutable_timestamp());
  k.set_frame_id(frame);
  k.set_width(c.width());
  k.set_height(c.height());
  k.set_distortion_model(c.distortion_model().empty() ? "plumb_bob" : c.distortion_model());
  for (double v : c.d()) k.add_d(v);
  for (double v : c.k()) k.add_k(v);
  for (double v : c.r()) k.add_r(v);
  if (c.r_size() == 0)
    for (double v : {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) k.add_r(v);
  for (double v : c.p()) k.add_p(v);
  if (c.p_size() == 0 && c.k_size() == 9) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) k.add_p(c.k(3 * i + j));
      k.add_p(0.0);
    }
  }
  Add(topic + "/foxglove/calibration", k, out);
}

void AddPose(const std::string& topic, int64_t stamp, const pb::Pose& pose, bool with_tf,
             const std::string& frame, std::vector<FoxgloveMessage>* out) {
  foxglove::PoseInFrame p;
  SetStamp(stamp, p.mutable_timestamp());
  p.set_frame_id(ParentOf(pose));
  ToFoxglovePose(pose, p.mutable_pose());
  Add(topic + "/foxglove/pose", p, out);
  if (!with_tf) return;
  foxglove::FrameTransform t;
  SetStamp(stamp, t.mutable_timestamp());
  t.set_parent_frame_id(ParentOf(pose));
  t.set_child_frame_id(frame);
  t.mutable_translation()->set_x(pose.position().x());
  t.mutable_translation()->set_y(pose.position().y());
  t.mutable_translation()->set_z(pose.position().z());
  t.mutable_rotation()->set_x(pose.orientation().x());
  t.mutable_rotation()->set_y(pose.orientation().y());
  t.mutable_rotation()->set_z(pose.orientation().z());
  t.mutable_rotation()->set_w(pose.orientation().w());
  Add(topic + "/foxglove/tf", t, out);
}

}  // namespace

std::vector<std::pair<std::string, const google::protobuf::Descriptor*>> FoxgloveChannelsFor(
    const std::string& p2i_type) {
  const auto* raw = foxglove::RawImage::descriptor();
  const auto* cal = foxglove::CameraCalibration::descriptor();
  const auto* tf = foxglove::FrameTransform::descriptor();
  const auto* pose = foxglove::PoseInFrame::descriptor();
  if (p2i_type == "RgbdFrame")
    return {{"/foxglove/rgb", raw}, {"/foxglove/depth", raw}, {"/foxglove/calibration", cal},
            {"/foxglove/tf", tf}};
  if (p2i_type == "View")
    return {{"/foxglove/rgb", raw}, {"/foxglove/depth", raw}, {"/foxglove/pose", pose},
            {"/foxglove/tf", tf}};
  if (p2i_type == "CameraInfo") return {{"/foxglove/calibration", cal}};
  if (p2i_type == "PoseStamped") return {{"/foxglove/pose", pose}, {"/foxglove/tf", tf}};
  if (p2i_type == "PoseRequest") return {{"/foxglove/pose", pose}};
  return {};
}

std::vector<FoxgloveMessage> ToFoxglove(const std::string& topic, const msgs::WireMessage& m) {
  std::vector<FoxgloveMessage> out;
  pb::Header h;
  std::string error;
  if (!msgs::PeekHeader(m.header, &h, &error)) return out;
  const int64_t stamp = h.capture_stamp_ns() ? h.capture_stamp_ns() : h.publish_stamp_ns();
  switch (h.type()) {
    case pb::RGBD_FRAME: {
      msgs::RgbdFrame f;
      if (!msgs::Decode(m, &f, &error)) return out;
      const std::string frame = FrameOf(h, f.meta.has_pose() ? &f.meta.pose() : nullptr);
      AddRgb(topic, stamp, frame, f.rgb, &out);
      AddDepth(topic, stamp, frame, f.depth, &out);
      if (f.meta.has_camera_info()) AddCalibration(topic, stamp, frame, f.meta.camera_info(), &out);
      if (f.meta.has_pose()) AddPose(topic, stamp, f.meta.pose(), true, frame, &out);
      break;
    }
    case pb::VIEW: {
      msgs::View v;
      if (!msgs::Decode(m, &v, &error)) return out;
      const std::string frame = FrameOf(h, &v.meta.pose());
      AddRgb(topic, stamp, frame, v.rgb, &out);
      AddDepth(topic, stamp, frame, v.depth, &out);
      AddPose(topic, stamp, v.meta.pose(), true, frame, &out);
      break;
    }
    case pb::CAMERA_INFO: {
      pb::CameraInfo c;
      if (!msgs::Decode(m, &c, &error)) return out;
      AddCalibration(topic, stamp, FrameOf(h, nullptr), c, &out);
      break;
    }
    case pb::POSE: {
      pb::PoseStamped p;
      if (!msgs::Decode(m, &p, &error)) return out;
      AddPose(topic, stamp, p.pose(), true, FrameOf(h, &p.pose()), &out);
      break;
    }
    case pb::POSE_REQUEST: {
      pb::PoseRequest p;
      if (!msgs::Decode(m, &p, &error)) return out;
      AddPose(topic, stamp, p.pose(), false, "", &out);
      break;
    }
    default:
      break;
  }
  return out;
}

}  // namespace p2i::recording
