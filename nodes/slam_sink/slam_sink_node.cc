/// @file slam_sink_node.cc
/// @brief SlamSinkNode.
#include "nodes/slam_sink/slam_sink_node.h"

#include <chrono>
#include <cmath>
#include <exception>

#include "nodes/slam_sink/message_conversion.h"

namespace p2i::slam_sink {

SlamSinkNode::SlamSinkNode(const runtime::NodeArgs& args) : runtime::Node("slam_sink", args) {
  SlamSinkOptions o;
  o.writer.out_dir = Declare<std::string>("out_dir", "slam_sequence",
                                          "folder of the TUM RGB-D sequence (created)");
  o.writer.append = Declare<bool>("append", false, "append to an existing sequence in out_dir");
  o.writer.fsync = Declare<bool>("fsync", false, "fsync every image and index line");
  o.writer.png_compression = Declare<int>("png_compression", 1, "PNG compression 0..9");
  o.writer.write_associations =
      Declare<bool>("write_associations", true, "write associations.txt (ORB-SLAM format)");
  o.check = Declare<bool>("check", true, "check synthetic views with RGB-D odometry");
  o.policy = Declare<std::string>("policy", "flag", "failing views: flag (write, mark) | drop");
  o.write_real = Declare<bool>("write_real", true, "write frames received on real_topic");
  o.checker.method = Declare<std::string>("odometry_method", o.checker.method,
                                          "rgbd_icp | icp | rgbd (OpenCV rgbd module)");
  o.checker.max_translation_error_m = Declare<double>(
      "max_translation_error_m", o.checker.max_translation_error_m, "check threshold (m)");
  o.checker.max_rotation_error_deg = Declare<double>(
      "max_rotation_error_deg", o.checker.max_rotation_error_deg, "check threshold (deg)");
  o.checker.min_coverage =
      Declare<double>("min_coverage", o.checker.min_coverage, "views below this coverage fail");
  o.checker.min_valid_depth_fraction =
      Declare<double>("min_valid_depth_fraction", o.checker.min_valid_depth_fraction,
                      "views with fewer valid depth pixels fail");
  o.checker.min_depth_m = Declare<double>("min_depth_m", o.checker.min_depth_m, "odometry range");
  o.checker.max_depth_m = Declare<double>("max_depth_m", o.checker.max_depth_m, "odometry range");
  o.checker.max_baseline_m = Declare<double>("max_baseline_m", o.checker.max_baseline_m,
                                             "larger motions are not verified");
  o.checker.max_baseline_deg = Declare<double>("max_baseline_deg", o.checker.max_baseline_deg,
                                               "larger rotations are not verified");
  const std::string camera_info_file =
      Declare<std::string>("camera_info_file", "", "ROS camera_info YAML of the views");
  const std::string views_topic = Declare<std::string>("views_topic", "views", "View topic");
  const std::string real_topic =
      Declare<std::string>("real_topic", "", "RgbdFrame topic of real frames ('' = off)");
  const std::string camera_info_topic = Declare<std::string>(
      "camera_info_topic", "camera_info", "CameraInfo topic used without camera_info_file");
  const double summary_period =
      Declare<double>("summary_period", 5.0, "rewrite summary.json every N s (0 = at exit)");

  ParametersDone();  // unknown parameters and --help stop here, before out_dir is created
  std::optional<scene::CameraInfo> camera;
  if (!camera_info_file.empty()) camera = scene::CameraInfo::FromYamlFile(camera_info_file);
  sink_ = std::make_unique<SlamSink>(o, camera);
  Log().info("writing the TUM RGB-D sequence to {} (check {}, policy {})", o.writer.out_dir,
             o.check ? (camera ? "on" : "waiting for camera_info") : "off", o.policy);

  views_sub_ = Subscribe<msgs::View>(views_topic, [this, views_topic](const msgs::View& view) {
    Count("views_received");
    SinkFrame frame;
    try {
      frame = FrameFromView(view, Resolve(views_topic));
    } catch (const std::exception& e) {
      Count("bad_frames");
      WarnThrottled("bad_view", std::string("dropping a view: ") + e.what());
      return;
    }
    OnFrame(frame);
  });
  if (!real_topic.empty()) {
    real_sub_ = Subscribe<msgs::RgbdFrame>(
        real_topic, [this, real_topic](const msgs::RgbdFrame& msg) {
          Count("real_received");
          SinkFrame frame;
          try {
            frame = FrameFromRgbd(msg, Resolve(real_topic));
          } catch (const std::exception& e) {
            Count("bad_frames");
            WarnThrottled("bad_real", std::string("dropping a real frame: ") + e.what());
            return;
          }
          OnFrame(frame);
        });
  }
  if (!camera && o.check && !camera_info_topic.empty()) {
    camera_sub_ = Subscribe<msgs::pb::CameraInfo>(
        camera_info_topic, [this](const msgs::pb::CameraInfo& msg) {
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
  if (summary_period > 0.0) {
    AddTimer(std::chrono::nanoseconds(static_cast<int64_t>(summary_period * 1e9)), [this] {
      try {
        sink_->WriteSummary();
      } catch (const std::exception& e) {
        WarnThrottled("summary", e.what());
      }
    });
  }
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
