/// @file live_source.cc
/// @brief LiveSource: a live device's frames, matched to poses by capture stamp.
#include "nodes/camera/live_source.h"

#include "convert/pose.h"
#include "scene/sim_scene.h"

namespace p2i::nodes {

LiveSource::LiveSource(const std::string& backend, const LiveSourceOptions& options)
    : backend_name_(backend), options_(options) {
  stamp_offset_ns_ = static_cast<int64_t>(options_.stamp_offset * 1e9);
  try {
    device_ = backend == "aravis" ? OpenAravisBackend(options_.aravis)
                                  : OpenLibcameraBackend(options_.libcamera);
  } catch (const runtime::StartupError&) {
    throw;
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  OpenCalibration();
}

LiveSource::~LiveSource() { Stop(); }

void LiveSource::OpenCalibration() {
  const int w = device_->width(), h = device_->height();
  const std::string& file = options_.camera_info_file;
  if (file.empty()) {
    camera_ = scene::SimScene::DefaultCamera(w, h);
    nominal_camera_ = true;
    return;
  }
  try {
    camera_ = scene::CameraInfo::FromYamlFile(file);
  } catch (const std::exception& e) {
    throw runtime::StartupError(e.what());
  }
  if (camera_.image_width == w && camera_.image_height == h) return;
  if (static_cast<int64_t>(camera_.image_width) * h !=
      static_cast<int64_t>(camera_.image_height) * w) {
    throw runtime::StartupError(
        "camera_info_file '" + file + "' is for " + std::to_string(camera_.image_width) + "x" +
        std::to_string(camera_.image_height) + " but the device streams " + std::to_string(w) +
        "x" + std::to_string(h) +
        " (another aspect ratio): calibrate at this size or set width/height");
  }
  camera_ = camera_.Scaled(w, h);
}

void LiveSource::Start(runtime::Node& node, Emit emit) {
  node_ = &node;
  emit_ = std::move(emit);
  if (nominal_camera_) {
    node.Log().warn("no camera_info_file: publishing a nominal pinhole (f = 525 W / 640) for {}x{}",
                    camera_.image_width, camera_.image_height);
  }
  const bool topic = options_.pose_mode == "topic";
  if (topic) {
    FramePoseMatcher::Options mo;
    mo.tolerance_ns = static_cast<int64_t>(options_.pose_tolerance * 1e9);
    mo.max_wait_ns = static_cast<int64_t>(options_.pose_wait * 1e9);
    mo.max_pending = static_cast<size_t>(options_.max_pending);
    matcher_.emplace(mo);
    pose_sub_ = node.Subscribe<msgs::pb::PoseStamped>("pose", [this](const msgs::pb::PoseStamped& m) {
      matcher_->AddPose(m.header().capture_stamp_ns(), convert::FromMsg(m.pose()));
      PublishMatched();
    });
  }
  node.Log().info("{} backend: {}; poses {}", backend_name_, device_->Describe(),
                  topic ? "from " + node.Resolve("pose") + " within " +
                              std::to_string(options_.pose_tolerance) + " s"
                        : "none");
  // Frames waiting for a pose time out even when no pose and no frame arrives.
  node.AddTimer(std::chrono::milliseconds(20), [this] { PublishMatched(); });
  device_->Start([this](LiveFrame&& f) { OnFrame(std::move(f)); },
                 [this](const std::string& error) {
                   // Thrown on the executor thread: Spin() ends and the node exits with 1.
                   node_->GetExecutor().Post([error] { throw std::runtime_error(error); });
                 });
}

void LiveSource::Stop() {
  if (device_) device_->Stop();
}

void LiveSource::OnFrame(LiveFrame&& frame) {
  std::lock_guard<std::mutex> lock(handoff_mutex_);
  // Bounded: when the executor falls behind, the oldest frames go (counted).
  while (handoff_.size() >= 4) {
    handoff_.pop_front();
    node_->Count("frames_dropped_backlog");
  }
  handoff_.push_back(std::move(frame));
  if (!drain_posted_) {
    drain_posted_ = true;
    node_->GetExecutor().Post([this] { Drain(); });
  }
}

void LiveSource::Drain() {
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
      emit_(f.rgb, f.depth, nullptr, f.stamp_ns);
    }
  }
  if (matcher_) PublishMatched();
  SyncCounters();
}

void LiveSource::PublishMatched() {
  if (!matcher_) return;
  for (const MatchedFrame& m : matcher_->Poll(runtime::NowNs())) {
    emit_(m.frame.rgb, m.frame.depth, &m.pose, m.frame.stamp_ns);
  }
  SyncCounters();
}

void LiveSource::WarnDropped(const FramePoseMatcher::Counters& c) {
  const FramePoseMatcher::Counters& r = reported_;
  if (c.dropped() <= r.dropped()) return;
  node_->Count("frames_dropped_no_pose", c.dropped() - r.dropped());
  std::string why = "too many frames waiting (max_pending)";
  if (c.dropped_timeout > r.dropped_timeout) {
    why = "no pose on " + node_->Resolve("pose") + " brackets it within pose_wait";
  } else if (c.dropped_gap > r.dropped_gap) {
    why = "the poses around it are farther apart than pose_tolerance";
  } else if (c.dropped_too_old > r.dropped_too_old) {
    why = "it is older than the oldest pose kept (the pose stream began after it, or the "
          "clocks disagree)";
  }
  node_->WarnThrottled("no_pose", "dropping frames without a pose: " + why +
                                      " (counter frames_dropped_no_pose)");
}

void LiveSource::SyncCounters() {
  const auto add = [this](const char* key, uint64_t now, uint64_t* before) {
    if (now > *before) node_->Count(key, now - *before);
    *before = now;
  };
  if (matcher_) {
    const FramePoseMatcher::Counters& c = matcher_->counters();
    WarnDropped(c);
    add("frames_dropped_pose_too_old", c.dropped_too_old, &reported_.dropped_too_old);
    add("frames_dropped_pose_gap", c.dropped_gap, &reported_.dropped_gap);
    add("frames_dropped_pose_timeout", c.dropped_timeout, &reported_.dropped_timeout);
    add("frames_dropped_pose_overflow", c.dropped_overflow, &reported_.dropped_overflow);
    add("poses_duplicate", c.poses_duplicate, &reported_.poses_duplicate);
    add("poses_too_old", c.poses_too_old, &reported_.poses_too_old);
  }
  const LiveBackend::Stats s = device_->GetStats();
  add("frames_captured", s.frames, &reported_stats_.frames);
  add("frames_incomplete", s.incomplete, &reported_stats_.incomplete);
  add("frames_without_depth", s.depth_unmatched, &reported_stats_.depth_unmatched);
}

}  // namespace p2i::nodes
