/// @file camera_node.cc
/// @brief Camera node backends: sim and replay.
#include "nodes/camera/camera_node.h"

#include <filesystem>

#include "nodes/camera/msg_convert.h"
#include "scene/dataset_loader.h"
#include "scene/dataset_trajectories.h"
#include "scene/image_ops.h"

namespace p2i::nodes {
namespace {

std::chrono::nanoseconds Period(double rate_hz) {
  return std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate_hz));
}

}  // namespace

CameraNode::CameraNode(const runtime::NodeArgs& args) : Node("camera", args) {
  const std::string backend = Declare<std::string>("backend", "sim", "sim | replay");
  frame_id_ = Declare<std::string>("frame_id", "camera", "frame of the images");
  if (backend == "sim") {
    SetUpSim();
  } else if (backend == "replay") {
    SetUpReplay();
  } else {
    throw runtime::StartupError("backend '" + backend +
                                "' is not available (this build has: sim, replay)");
  }
  msgs::pb::CameraInfo info;
  info.mutable_header()->set_frame_id(frame_id_);
  info.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
  ToMsg(camera_, &info);
  runtime::PublisherOptions latched;
  latched.latched = true;
  info_pub_ = Advertise<msgs::pb::CameraInfo>("camera_info", latched);
  info_pub_->Publish(info);
  rgbd_pub_ = Advertise<msgs::RgbdFrame>("rgbd");
}

void CameraNode::SetUpSim() {
  const std::string scene_spec =
      Declare<std::string>("scene", "builtin:small_office", "builtin:NAME or scene YAML file");
  const bool kinect = Declare<bool>("kinect", false, "Kinect-like sensor noise and holes");
  rate_ = Declare<double>("rate", 20.0, "frames per second");
  const int width = Declare<int>("width", 0, "image width (0 = calibration's or 640)");
  const int height = Declare<int>("height", 0, "image height (0 = calibration's or 480)");
  const std::string camera_file =
      Declare<std::string>("camera_info_file", "", "ROS camera_info YAML; empty = default");
  const std::string pose_mode =
      Declare<std::string>("pose_mode", "topic", "topic (render at poses on 'pose') | trajectory");
  const std::string spec = Declare<std::string>("trajectory", "arm_sweep",
                                                "pose_mode trajectory: trajectory spec");
  const int index = Declare<int>("trajectory_index", 0, "which trajectory of a multi spec");
  loop_ = Declare<bool>("loop", true, "pose_mode trajectory: restart at the end");
  exit_at_end_ = Declare<bool>("exit_at_end", false, "stop when a non-looping trajectory ends");
  if (!(rate_ > 0.0) || width < 0 || height < 0) {
    throw runtime::StartupError("rate must be > 0, width and height >= 0");
  }
  try {
    sim_.emplace(scene::SimScene::FromSpec(scene_spec));
    if (kinect) sim_->set_sensor_options(scene::SimSensorOptions::Kinect());
    if (!camera_file.empty()) {
      camera_ = scene::CameraInfo::FromYamlFile(camera_file);
      if (width > 0 && height > 0) camera_ = camera_.Scaled(width, height);
    } else {
      camera_ = scene::SimScene::DefaultCamera(width > 0 ? width : 640, height > 0 ? height : 480);
    }
    if (pose_mode == "trajectory") {
      auto all = scene::ResolveTrajectorySpec(spec, &*sim_);
      if (index < 0 || static_cast<size_t>(index) >= all.size()) {
        throw runtime::StartupError("trajectory_index out of range for '" + spec + "'");
      }
      trajectory_ = std::move(all[index]);
    } else if (pose_mode != "topic") {
      throw runtime::StartupError("pose_mode '" + pose_mode + "' must be topic or trajectory");
    }
  } catch (const runtime::StartupError&) {
    throw;
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  if (pose_mode == "topic") {
    runtime::SubscriberOptions options;
    options.latest_only = true;
    pose_sub_ = Subscribe<msgs::pb::PoseStamped>(
        "pose",
        [this](const msgs::pb::PoseStamped& msg) {
          if (pending_pose_) Count("poses_skipped");
          pending_pose_ = FromMsg(msg.pose());
          pending_stamp_ns_ = msg.header().capture_stamp_ns();
        },
        options);
  }
  Log().info("sim backend: {} at {}x{}, {} Hz, poses from {}", scene_spec, camera_.image_width,
             camera_.image_height, rate_,
             pose_mode == "topic" ? "topic " + Resolve("pose") : "trajectory '" + spec + "'");
  AddTimer(Period(rate_), [this] { OnSimTick(); });
}

void CameraNode::OnSimTick() {
  if (finished_) return;
  scene::Pose pose;
  int64_t stamp = 0;
  if (trajectory_.empty()) {
    if (!pending_pose_) return;
    pose = *pending_pose_;
    stamp = pending_stamp_ns_;
    pending_pose_.reset();
  } else {
    pose = trajectory_[trajectory_index_].pose;
    stamp = runtime::NowNs();
    if (++trajectory_index_ >= trajectory_.size()) {
      trajectory_index_ = 0;
      Count("laps");
      if (!loop_) {
        finished_ = true;
        if (exit_at_end_) Stop();
      }
    }
  }
  PublishSample(sim_->Render(pose, camera_, static_cast<double>(stamp) * 1e-9), stamp);
}

void CameraNode::SetUpReplay() {
  const std::string path = Declare<std::string>("dataset", "", "dataset folder to play");
  const std::string format =
      Declare<std::string>("format", "auto", "auto | capture | tum | 7scenes");
  const int invalid = Declare<int>("invalid_depth", 65535, "7-Scenes raw depth meaning invalid");
  const std::string camera_file =
      Declare<std::string>("camera_info_file", "", "override the dataset's calibration");
  rate_ = Declare<double>("rate", 0.0, "frames per second; 0 = the recorded stamps");
  rate_scale_ = Declare<double>("rate_scale", 1.0, "speed factor on the recorded rate");
  out_width_ = Declare<int>("width", 0, "centre-crop + resize to this width (0 = native)");
  out_height_ = Declare<int>("height", 0, "centre-crop + resize to this height (0 = native)");
  loop_ = Declare<bool>("loop", false, "start again at the end");
  exit_at_end_ = Declare<bool>("exit_at_end", false, "stop the node at the end (no loop)");
  if (path.empty()) throw runtime::StartupError("replay needs the 'dataset' parameter");
  if (rate_ < 0.0 || !(rate_scale_ > 0.0)) {
    throw runtime::StartupError("rate must be >= 0 and rate_scale > 0");
  }
  if ((out_width_ > 0) != (out_height_ > 0) || out_width_ < 0) {
    throw runtime::StartupError("width and height must both be set (> 0) or both be 0");
  }
  try {
    scene::DatasetOptions options;
    options.format = format;
    options.seven_scenes_invalid_depth = invalid;
    options.camera_info_file = camera_file;
    dataset_ = scene::OpenDataset(path, options);
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  if (dataset_.empty()) throw runtime::StartupError("dataset '" + path + "' has no frames");
  camera_ = out_width_ > 0
                ? scene::CenterCropResizeCamera(dataset_.camera(), out_width_, out_height_)
                : dataset_.camera();
  Log().info("replay backend: {} frames from '{}' at {}", dataset_.size(), path,
             rate_ > 0.0 ? std::to_string(rate_) + " Hz"
                         : "the recorded rate x " + std::to_string(rate_scale_));
  lap_start_ = std::chrono::steady_clock::now();
  // A short tick: frames go out when their (scaled) recorded time has come.
  AddTimer(std::chrono::milliseconds(2), [this] { OnReplayTick(); });
}

void CameraNode::OnReplayTick() {
  if (finished_) return;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - lap_start_).count();
  const auto due_time = [&](size_t i) {
    if (rate_ > 0.0) return static_cast<double>(i) / rate_;
    return (dataset_.frames()[i].stamp - dataset_.frames().front().stamp) / rate_scale_;
  };
  if (due_time(next_frame_) > elapsed) return;
  // Fell behind: publish the newest due frame, count the ones jumped over.
  size_t i = next_frame_;
  while (i + 1 < dataset_.size() && due_time(i + 1) <= elapsed) ++i;
  if (i > next_frame_) Count("frames_skipped", i - next_frame_);
  scene::RgbdSample sample = dataset_.Load(i);
  if (out_width_ > 0) sample = scene::CenterCropResizeSample(sample, out_width_, out_height_);
  PublishSample(sample, runtime::NowNs());
  next_frame_ = i + 1;
  if (next_frame_ >= dataset_.size()) {
    Count("laps");
    if (loop_) {
      next_frame_ = 0;
      lap_start_ = std::chrono::steady_clock::now() + Period(rate_ > 0.0 ? rate_ : 20.0);
    } else {
      finished_ = true;
      Log().info("replay finished ({} frames)", dataset_.size());
      if (exit_at_end_) Stop();
    }
  }
}

void CameraNode::PublishSample(const scene::RgbdSample& sample, int64_t capture_stamp_ns) {
  msgs::RgbdFrame frame;
  frame.meta.mutable_header()->set_capture_stamp_ns(capture_stamp_ns);
  frame.meta.mutable_header()->set_frame_id(frame_id_);
  ToMsg(camera_, frame.meta.mutable_camera_info());
  ToMsg(sample.pose, frame.meta.mutable_pose());
  frame.rgb = ToImage(sample.rgb);
  frame.depth = ToImage(sample.depth);
  rgbd_pub_->Publish(frame);
  Count("frames_published");
}

}  // namespace p2i::nodes
