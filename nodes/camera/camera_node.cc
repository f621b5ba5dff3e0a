/// @file camera_node.cc
/// @brief Camera node backends: sim, replay and the live ones (aravis, libcamera).
#include "nodes/camera/camera_node.h"

#include <filesystem>

#include "convert/camera_info.h"
#include "convert/image.h"
#include "convert/pose.h"
#include "scene/dataset_loader.h"
#include "scene/dataset_trajectories.h"
#include "scene/image_ops.h"

namespace p2i::nodes {
namespace {

// Larger than any camera the nodes serve (and than the wire's image limits allow to decode).
constexpr int kMaxImageSide = 8192;

std::chrono::nanoseconds Period(double rate_hz) {
  return std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate_hz));
}

}  // namespace

CameraNode::CameraNode(const runtime::NodeArgs& args) : Node("camera", args) {
  const std::string backend =
      Declare<std::string>("backend", "sim", "sim | replay | aravis | libcamera");
  frame_id_ = Declare<std::string>("frame_id", "camera", "frame of the images");
  if (backend == "sim") {
    SetUpSim();
  } else if (backend == "replay") {
    SetUpReplay();
  } else if (backend == "aravis" || backend == "libcamera") {
    SetUpLive(backend);
  } else {
    throw runtime::StartupError("backend '" + backend +
                                "' is not known (sim, replay, aravis, libcamera)");
  }
  msgs::pb::CameraInfo info;
  info.mutable_header()->set_frame_id(frame_id_);
  info.mutable_header()->set_capture_stamp_ns(runtime::NowNs());
  convert::ToMsg(camera_, &info);
  runtime::PublisherOptions latched;
  latched.latched = true;
  info_pub_ = Advertise<msgs::pb::CameraInfo>("camera_info", latched);
  info_pub_->Publish(info);
  rgbd_pub_ = Advertise<msgs::RgbdFrame>("rgbd");
  if (live_) {
    // Streaming starts last: every publisher exists before the first frame arrives.
    live_->Start([this](LiveFrame&& f) { OnLiveFrame(std::move(f)); },
                 [this](const std::string& error) {
                   // Thrown on the executor thread: Spin() ends and the node exits with 1.
                   GetExecutor().Post([error] { throw std::runtime_error(error); });
                 });
  }
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
  if (width > kMaxImageSide || height > kMaxImageSide) {
    throw runtime::StartupError("width " + std::to_string(width) + " x height " +
                                std::to_string(height) + ": at most " +
                                std::to_string(kMaxImageSide) + " pixels a side");
  }
  ParametersDone();
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
          pending_pose_ = convert::FromMsg(msg.pose());
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
  if (out_width_ > kMaxImageSide || out_height_ > kMaxImageSide) {
    throw runtime::StartupError("width and height: at most " + std::to_string(kMaxImageSide) +
                                " pixels a side");
  }
  ParametersDone();
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
  Publish(sample.rgb, sample.depth, &sample.pose, capture_stamp_ns);
}

void CameraNode::Publish(const cv::Mat& rgb, const cv::Mat& depth, const scene::Pose* pose,
                         int64_t capture_stamp_ns) {
  msgs::RgbdFrame frame;
  frame.meta.mutable_header()->set_capture_stamp_ns(capture_stamp_ns);
  frame.meta.mutable_header()->set_frame_id(frame_id_);
  convert::ToMsg(camera_, frame.meta.mutable_camera_info());
  if (pose != nullptr) convert::ToMsg(*pose, frame.meta.mutable_pose());
  frame.rgb = convert::ToImage(rgb);
  frame.depth = convert::ToImage(depth);
  rgbd_pub_->Publish(frame);
  Count("frames_published");
}

// ---------------------------------------------------------------------------------------------
// live backends

void CameraNode::SetUpLive(const std::string& backend) {
  const std::string camera_file = Declare<std::string>(
      "camera_info_file", "", "ROS camera_info YAML (calib/); empty = a nominal pinhole");
  const int width = Declare<int>("width", 0, "image width (0 = the device's)");
  const int height = Declare<int>("height", 0, "image height (0 = the device's)");
  const std::string pose_mode = Declare<std::string>(
      "pose_mode", "topic", "topic (pose from 'pose' by capture stamp) | none (no pose)");
  const double tolerance = Declare<double>(
      "pose_tolerance", 0.05, "s: both poses bracketing a frame's stamp must be this close");
  const double wait = Declare<double>("pose_wait", 0.2, "s: a frame may wait for a newer pose");
  const int max_pending = Declare<int>("max_pending", 8, "frames waiting for a pose at most");
  const double stamp_offset =
      Declare<double>("stamp_offset", 0.0, "s subtracted from the host reception stamp");
  const int buffers = Declare<int>("buffers", backend == "aravis" ? 8 : 4, "stream buffers");
  if (width < 0 || height < 0) throw runtime::StartupError("width and height must be >= 0");
  if (width > kMaxImageSide || height > kMaxImageSide) {
    throw runtime::StartupError("width and height: at most " + std::to_string(kMaxImageSide) +
                                " pixels a side");
  }
  // Each backend's own parameters are declared before ParametersDone(), so that they are known
  // (and shown by --help) before anything is opened.
  AravisOptions aravis;
  LibcameraOptions libcamera;
  if (backend == "aravis") {
    aravis.device = Declare<std::string>("device", "", "Aravis device id or IP; empty = the first");
    aravis.pixel_format = Declare<std::string>(
        "pixel_format", "", "Mono8 | Mono16 | RGB8 | BGR8 | Bayer{RG,GR,GB,BG}8; empty = keep");
    aravis.width = width;
    aravis.height = height;
    aravis.frame_rate = Declare<double>("frame_rate", 0.0, "Hz; 0 = the device's");
    aravis.exposure_us = Declare<double>("exposure_us", 0.0, "us; 0 = the device's");
    aravis.depth_device =
        Declare<std::string>("depth_device", "", "second device streaming Mono16 depth");
    aravis.depth_scale = Declare<double>("depth_scale", 0.001, "metres per depth unit");
    aravis.depth_tolerance = Declare<double>(
        "depth_tolerance", 0.02, "s: max stamp difference between colour and depth");
    aravis.buffers = buffers;
  } else {
    libcamera.camera = Declare<std::string>("camera", "", "libcamera camera id; empty = the first");
    libcamera.width = width;
    libcamera.height = height;
    libcamera.buffers = buffers;
  }
  ParametersDone();
  if (pose_mode != "topic" && pose_mode != "none") {
    throw runtime::StartupError("pose_mode '" + pose_mode + "' must be topic or none");
  }
  if (!(tolerance >= 0.0) || !(wait >= 0.0) || max_pending < 1) {
    throw runtime::StartupError("pose_tolerance and pose_wait must be >= 0, max_pending >= 1");
  }
  stamp_offset_ns_ = static_cast<int64_t>(stamp_offset * 1e9);
  try {
    if (backend == "aravis") {
      live_ = OpenAravisBackend(aravis);
    } else {
      live_ = OpenLibcameraBackend(libcamera);
    }
  } catch (const runtime::StartupError&) {
    throw;
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  const int w = live_->width(), h = live_->height();
  if (!camera_file.empty()) {
    try {
      camera_ = scene::CameraInfo::FromYamlFile(camera_file);
    } catch (const std::exception& e) {
      throw runtime::StartupError(e.what());
    }
    if (camera_.image_width != w || camera_.image_height != h) {
      if (static_cast<int64_t>(camera_.image_width) * h !=
          static_cast<int64_t>(camera_.image_height) * w) {
        throw runtime::StartupError(
            "camera_info_file '" + camera_file + "' is for " +
            std::to_string(camera_.image_width) + "x" + std::to_string(camera_.image_height) +
            " but the device streams " + std::to_string(w) + "x" + std::to_string(h) +
            " (another aspect ratio): calibrate at this size or set width/height");
      }
      camera_ = camera_.Scaled(w, h);
    }
  } else {
    camera_ = scene::SimScene::DefaultCamera(w, h);
    Log().warn("no camera_info_file: publishing a nominal pinhole (f = 525 W / 640) for {}x{}", w,
               h);
  }
  if (pose_mode == "topic") {
    FramePoseMatcher::Options mo;
    mo.tolerance_ns = static_cast<int64_t>(tolerance * 1e9);
    mo.max_wait_ns = static_cast<int64_t>(wait * 1e9);
    mo.max_pending = static_cast<size_t>(max_pending);
    matcher_.emplace(mo);
    pose_sub_ = Subscribe<msgs::pb::PoseStamped>("pose", [this](const msgs::pb::PoseStamped& m) {
      matcher_->AddPose(m.header().capture_stamp_ns(), convert::FromMsg(m.pose()));
      PublishMatched();
    });
  }
  Log().info("{} backend: {}; poses {}", backend, live_->Describe(),
             pose_mode == "topic" ? "from " + Resolve("pose") + " within " +
                                        std::to_string(tolerance) + " s"
                                  : "none");
  // Frames waiting for a pose time out even when no pose and no frame arrives.
  AddTimer(std::chrono::milliseconds(20), [this] { PublishMatched(); });
}

void CameraNode::OnLiveFrame(LiveFrame&& frame) {
  std::lock_guard<std::mutex> lock(handoff_mutex_);
  // Bounded: when the executor falls behind, the oldest frames go (counted).
  while (handoff_.size() >= 4) {
    handoff_.pop_front();
    Count("frames_dropped_backlog");
  }
  handoff_.push_back(std::move(frame));
  if (!drain_posted_) {
    drain_posted_ = true;
    GetExecutor().Post([this] { DrainLiveFrames(); });
  }
}

void CameraNode::DrainLiveFrames() {
  std::deque<LiveFrame> frames;
  {
    std::lock_guard<std::mutex> lock(handoff_mutex_);
    frames.swap(handoff_);
    drain_posted_ = false;
  }
  for (LiveFrame& f : frames) {
    f.stamp_ns -= stamp_offset_ns_;
    if (f.depth.empty()) f.depth = cv::Mat::zeros(f.rgb.size(), CV_32FC1);  // all invalid
    if (matcher_) {
      matcher_->AddFrame(std::move(f), runtime::NowNs());
    } else {
      Publish(f.rgb, f.depth, nullptr, f.stamp_ns);
    }
  }
  if (matcher_) PublishMatched();
  SyncLiveCounters();
}

void CameraNode::PublishMatched() {
  if (!matcher_) return;
  for (const MatchedFrame& m : matcher_->Poll(runtime::NowNs())) {
    Publish(m.frame.rgb, m.frame.depth, &m.pose, m.frame.stamp_ns);
  }
  SyncLiveCounters();
}

void CameraNode::SyncLiveCounters() {
  const auto add = [this](const char* key, uint64_t now, uint64_t* before) {
    if (now > *before) Count(key, now - *before);
    *before = now;
  };
  if (matcher_) {
    const FramePoseMatcher::Counters& c = matcher_->counters();
    const FramePoseMatcher::Counters& r = reported_;
    if (c.dropped() > r.dropped()) {
      Count("frames_dropped_no_pose", c.dropped() - r.dropped());
      std::string why = "too many frames waiting (max_pending)";
      if (c.dropped_timeout > r.dropped_timeout) {
        why = "no pose on " + Resolve("pose") + " brackets it within pose_wait";
      } else if (c.dropped_gap > r.dropped_gap) {
        why = "the poses around it are farther apart than pose_tolerance";
      } else if (c.dropped_too_old > r.dropped_too_old) {
        why = "it is older than the oldest pose kept (the pose stream began after it, or the "
              "clocks disagree)";
      }
      WarnThrottled("no_pose", "dropping frames without a pose: " + why +
                                   " (counter frames_dropped_no_pose)");
    }
    add("frames_dropped_pose_too_old", c.dropped_too_old, &reported_.dropped_too_old);
    add("frames_dropped_pose_gap", c.dropped_gap, &reported_.dropped_gap);
    add("frames_dropped_pose_timeout", c.dropped_timeout, &reported_.dropped_timeout);
    add("frames_dropped_pose_overflow", c.dropped_overflow, &reported_.dropped_overflow);
    add("poses_duplicate", c.poses_duplicate, &reported_.poses_duplicate);
    add("poses_too_old", c.poses_too_old, &reported_.poses_too_old);
  }
  if (live_) {
    const LiveBackend::Stats s = live_->GetStats();
    add("frames_captured", s.frames, &reported_stats_.frames);
    add("frames_incomplete", s.incomplete, &reported_stats_.incomplete);
    add("frames_without_depth", s.depth_unmatched, &reported_stats_.depth_unmatched);
  }
}

void CameraNode::OnShutdown() {
  if (live_) live_->Stop();
}

}  // namespace p2i::nodes
