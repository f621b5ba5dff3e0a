/// @file camera_node.cc
/// @brief CameraNode: options -> source -> publishers.
#include "nodes/camera/camera_node.h"

#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "nodes/camera/live_source.h"
#include "nodes/camera/replay_source.h"
#include "nodes/camera/sim_source.h"

namespace p2i::nodes {
namespace {

/// The source of the selected backend (options validated).
std::unique_ptr<FrameSource> OpenSource(const CameraOptions& o) {
  if (o.backend == "sim") return std::make_unique<SimSource>(o.sim);
  if (o.backend == "replay") return std::make_unique<ReplaySource>(o.replay);
  return std::make_unique<LiveSource>(o.backend, o.live);
}

}  // namespace

CameraNode::CameraNode(const runtime::NodeArgs& args) : Node("camera", args) {
  const CameraOptions options = CameraOptions::FromParameters(Params());
  options.Validate();  // std::invalid_argument: RunNode's configuration error, exit 2
  frame_id_ = options.frame_id;
  // Every backend's parameters are declared: unknown ones and --help stop here, before the
  // scene, dataset or device is opened.
  ParametersDone();
  source_ = OpenSource(options);

  msgs::pb::CameraInfo info;
  info.mutable_header()->set_frame_id(frame_id_);
  info.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
  convert::ToMsg(source_->camera(), &info);
  runtime::PublisherOptions latched;
  latched.latched = true;
  info_pub_ = Advertise<msgs::pb::CameraInfo>("camera_info", latched);
  info_pub_->Publish(info);
  rgbd_pub_ = Advertise<msgs::RgbdFrame>("rgbd");
  // Frames start last: every publisher exists before the first one.
  source_->Start(*this, [this](const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose* pose,
                               int64_t stamp_ns) { Publish(rgb, depth, pose, stamp_ns); });
}

void CameraNode::Publish(const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose* pose,
                         int64_t capture_stamp_ns) {
  msgs::RgbdFrame frame;
  frame.meta.mutable_header()->set_capture_stamp_ns(capture_stamp_ns);
  frame.meta.mutable_header()->set_frame_id(frame_id_);
  convert::ToMsg(source_->camera(), frame.meta.mutable_camera_info());
  if (pose != nullptr) convert::ToMsg(*pose, frame.meta.mutable_pose());
  frame.rgb = convert::ToImage(rgb);
  frame.depth = convert::ToImage(depth);
  rgbd_pub_->Publish(frame);
  Count("frames_published");
}

void CameraNode::OnShutdown() {
  if (source_) source_->Stop();
}

}  // namespace p2i::nodes
