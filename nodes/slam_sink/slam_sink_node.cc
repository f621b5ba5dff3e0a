/// @file slam_sink_node.cc
/// @brief SlamSinkNode.
#include "nodes/slam_sink/slam_sink_node.h"

#include <chrono>
#include <cmath>
#include <exception>

#include "nodes/slam_sink/message_conversion.h"

namespace p2i::slam_sink {

SlamSinkNode::SlamSinkNode(const runtime::NodeArgs& args) : runtime::Node("slam_sink", args) {
  const SlamSinkNodeOptions o = SlamSinkNodeOptions::FromParameters(Params());
  ParametersDone();  // unknown parameters and --help stop here, before out_dir is created
  std::optional<scene::CameraInfo> camera;
  if (!o.camera_info_file.empty()) camera = scene::CameraInfo::FromYamlFile(o.camera_info_file);
  sink_ = std::make_unique<SlamSink>(o.sink, camera);
  Log().info("writing the TUM RGB-D sequence to {} (check {}, policy {})", o.sink.writer.out_dir,
             o.sink.check ? (camera ? "on" : "waiting for camera_info") : "off", o.sink.policy);
  SubscribeViews(o.views_topic);
  if (!o.real_topic.empty()) SubscribeRealFrames(o.real_topic);
  if (!camera && o.sink.check && !o.camera_info_topic.empty()) {
    SubscribeCameraInfo(o.camera_info_topic);
  }
  if (o.summary_period > 0.0) StartSummaryTimer(o.summary_period);
}

void SlamSinkNode::SubscribeViews(const std::string& topic) {
  views_sub_ = Subscribe<msgs::View>(topic, [this, topic](const msgs::View& view) {
    Count("views_received");
    SinkFrame frame;
    try {
      frame = FrameFromView(view, Resolve(topic));
    } catch (const std::exception& e) {
      Count("bad_frames");
      WarnThrottled("bad_view", std::string("dropping a view: ") + e.what());
      return;
    }
    OnFrame(frame);
  });
}

void SlamSinkNode::SubscribeRealFrames(const std::string& topic) {
  real_sub_ = Subscribe<msgs::RgbdFrame>(topic, [this, topic](const msgs::RgbdFrame& msg) {
    Count("real_received");
    SinkFrame frame;
    try {
      frame = FrameFromRgbd(msg, Resolve(topic));
    } catch (const std::exception& e) {
      Count("bad_frames");
      WarnThrottled("bad_real", std::string("dropping a real frame: ") + e.what());
      return;
    }
    OnFrame(frame);
  });
}

void SlamSinkNode::SubscribeCameraInfo(const std::string& topic) {
  camera_sub_ = Subscribe<msgs::pb::CameraInfo>(topic, [this](const msgs::pb::CameraInfo& msg) {
    try {
      const scene::CameraInfo c = CameraFromMsg(msg);
      if (sink_->SetCamera(c)) {
        Log().info("odometry check enabled with camera '{}' {}x{}", c.camera_name,
                   c.image_width, c.image_height);
      }
    } catch (const std::exception& e) {
      WarnThrottled("bad_camera", std::string("unusable camera_info: ") + e.what());
    }
  });
}

void SlamSinkNode::StartSummaryTimer(double period_s) {
  AddTimer(std::chrono::nanoseconds(static_cast<int64_t>(period_s * 1e9)), [this] {
    try {
      sink_->WriteSummary();
    } catch (const std::exception& e) {
      WarnThrottled("summary", e.what());
    }
  });
}

void SlamSinkNode::OnFrame(const SinkFrame& frame) {
  SlamSink::Outcome outcome;
  try {
    outcome = sink_->Process(frame);
  } catch (const std::exception& e) {
    Count("write_errors");
    WarnThrottled("write", std::string("frame not written: ") + e.what());
    return;
  }
  if (outcome.gap > 0) {
    Count("seq_missing", outcome.gap);
    Log().warn("{}: {} message(s) lost before seq {}", frame.source, outcome.gap, frame.seq);
  }
  if (outcome.written) Count("frames_written");
  if (outcome.check.status == CheckResult::Status::kFail) {
    Count("check_failed");
    if (!outcome.written) Count("dropped");
    Log().debug("view {} seq {} failed the check: {} (t_err {:.4f} m, r_err {:.3f} deg)",
                frame.source, frame.seq, outcome.check.reason, outcome.check.translation_error_m,
                outcome.check.rotation_error_deg);
  }
  UpdateStatus();
}

void SlamSinkNode::UpdateStatus() {
  if (const OdometryChecker* checker = sink_->checker()) {
    const CheckerStats& s = checker->stats();
    if (s.checked > 0) SetValue("pass_rate", s.pass_rate());
    if (s.translation_error_m.count > 0) {
      SetValue("odom_t_err_median_m", s.translation_error_m.median);
      SetValue("odom_r_err_median_deg", s.rotation_error_deg.median);
    }
  }
}

void SlamSinkNode::OnShutdown() {
  try {
    sink_->Close();
  } catch (const std::exception& e) {
    Log().error("finalising the sequence failed: {}", e.what());
  }
  Log().info("{}", sink_->SummaryLine());
}

}  // namespace p2i::slam_sink
