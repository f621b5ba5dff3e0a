/// @file camera_options.cc
/// @brief The camera node's parameters -> CameraOptions, and their validation.
#include "nodes/camera/camera_options.h"

#include "nodes/runtime/option_error.h"

namespace p2i::nodes {
namespace {

using runtime::CheckOption;

void DeclareSim(runtime::Parameters& p, SimSourceOptions* o) {
  o->scene = p.Declare<std::string>("scene", o->scene, "builtin:NAME or scene YAML file");
  o->kinect = p.Declare<bool>("kinect", o->kinect, "Kinect-like sensor noise and holes");
  o->rate = p.Declare<double>("rate", o->rate, "frames per second");
  o->width = p.Declare<int>("width", o->width, "image width (0 = calibration's or 640)");
  o->height = p.Declare<int>("height", o->height, "image height (0 = calibration's or 480)");
  o->camera_info_file = p.Declare<std::string>("camera_info_file", o->camera_info_file,
                                               "ROS camera_info YAML; empty = default");
  o->pose_mode = p.Declare<std::string>("pose_mode", o->pose_mode,
                                        "topic (render at poses on 'pose') | trajectory");
  o->trajectory = p.Declare<std::string>("trajectory", o->trajectory,
                                         "pose_mode trajectory: trajectory spec");
  o->trajectory_index =
      p.Declare<int>("trajectory_index", o->trajectory_index, "which trajectory of a multi spec");
  o->loop = p.Declare<bool>("loop", o->loop, "pose_mode trajectory: restart at the end");
  o->exit_at_end =
      p.Declare<bool>("exit_at_end", o->exit_at_end, "stop when a non-looping trajectory ends");
}

void DeclareReplay(runtime::Parameters& p, ReplaySourceOptions* o) {
  o->dataset = p.Declare<std::string>("dataset", o->dataset, "dataset folder to play");
  o->format = p.Declare<std::string>("format", o->format, "auto | capture | tum | 7scenes");
  o->invalid_depth =
      p.Declare<int>("invalid_depth", o->invalid_depth, "7-Scenes raw depth meaning invalid");
  o->camera_info_file = p.Declare<std::string>("camera_info_file", o->camera_info_file,
                                               "override the dataset's calibration");
  o->rate = p.Declare<double>("rate", o->rate, "frames per second; 0 = the recorded stamps");
  o->rate_scale =
      p.Declare<double>("rate_scale", o->rate_scale, "speed factor on the recorded rate");
  o->width =
      p.Declare<int>("width", o->width, "centre-crop + resize to this width (0 = native)");
  o->height =
      p.Declare<int>("height", o->height, "centre-crop + resize to this height (0 = native)");
  o->loop = p.Declare<bool>("loop", o->loop, "start again at the end");
  o->exit_at_end =
      p.Declare<bool>("exit_at_end", o->exit_at_end, "stop the node at the end (no loop)");
}

void DeclareAravis(runtime::Parameters& p, AravisOptions* o) {
  o->device =
      p.Declare<std::string>("device", o->device, "Aravis device id or IP; empty = the first");
  o->pixel_format =
      p.Declare<std::string>("pixel_format", o->pixel_format,
                             "Mono8 | Mono16 | RGB8 | BGR8 | Bayer{RG,GR,GB,BG}8; empty = keep");
  o->frame_rate = p.Declare<double>("frame_rate", o->frame_rate, "Hz; 0 = the device's");
  o->exposure_us = p.Declare<double>("exposure_us", o->exposure_us, "us; 0 = the device's");
  o->depth_device = p.Declare<std::string>("depth_device", o->depth_device,
                                           "second device streaming Mono16 depth");
  o->depth_scale = p.Declare<double>("depth_scale", o->depth_scale, "metres per depth unit");
  o->depth_tolerance = p.Declare<double>("depth_tolerance", o->depth_tolerance,
                                         "s: max stamp difference between colour and depth");
}

/// The live parameters; the stream size and buffers go to the selected device's options.
void DeclareLive(runtime::Parameters& p, const std::string& backend, LiveSourceOptions* o) {
  const bool aravis = backend == "aravis";
  int& width = aravis ? o->aravis.width : o->libcamera.width;
  int& height = aravis ? o->aravis.height : o->libcamera.height;
  int& buffers = aravis ? o->aravis.buffers : o->libcamera.buffers;
  o->camera_info_file =
      p.Declare<std::string>("camera_info_file", o->camera_info_file,
                             "ROS camera_info YAML (calib/); empty = a nominal pinhole");
  width = p.Declare<int>("width", width, "image width (0 = the device's)");
  height = p.Declare<int>("height", height, "image height (0 = the device's)");
  o->pose_mode = p.Declare<std::string>(
      "pose_mode", o->pose_mode, "topic (pose from 'pose' by capture stamp) | none (no pose)");
  o->pose_tolerance =
      p.Declare<double>("pose_tolerance", o->pose_tolerance,
                        "s: both poses bracketing a frame's stamp must be this close");
  o->pose_wait =
      p.Declare<double>("pose_wait", o->pose_wait, "s: a frame may wait for a newer pose");
  o->max_pending =
      p.Declare<int>("max_pending", o->max_pending, "frames waiting for a pose at most");
  o->stamp_offset = p.Declare<double>("stamp_offset", o->stamp_offset,
                                      "s subtracted from the host reception stamp");
  buffers = p.Declare<int>("buffers", buffers, "stream buffers");
  if (aravis) {
    DeclareAravis(p, &o->aravis);
  } else {
    o->libcamera.camera = p.Declare<std::string>("camera", o->libcamera.camera,
                                                 "libcamera camera id; empty = the first");
  }
}

/// width and height in [0, kMaxCameraImageSide].
void CheckSize(int width, int height) {
  const std::string rule = "be in [0, " + std::to_string(kMaxCameraImageSide) + "]";
  const std::string fix = "0 = the native size";
  CheckOption(width >= 0 && width <= kMaxCameraImageSide, "camera", "width", width, rule, fix);
  CheckOption(height >= 0 && height <= kMaxCameraImageSide, "camera", "height", height, rule,
              fix);
}

void ValidateSim(const SimSourceOptions& o) {
  CheckOption(o.rate > 0.0, "camera", "rate", o.rate, "be > 0",
              "frames per second, e.g. rate:=20");
  CheckSize(o.width, o.height);
  CheckOption(o.pose_mode == "topic" || o.pose_mode == "trajectory", "camera", "pose_mode",
              o.pose_mode, "be topic or trajectory",
              "pose_mode:=topic renders at the poses on 'pose'");
  CheckOption(o.trajectory_index >= 0, "camera", "trajectory_index", o.trajectory_index,
              "be >= 0", "0 = the first trajectory of the spec");
}

void ValidateReplay(const ReplaySourceOptions& o) {
  CheckOption(!o.dataset.empty(), "camera", "dataset", o.dataset,
              "name a dataset folder for backend replay", "e.g. dataset:=../shared/data/study-room");
  CheckOption(o.rate >= 0.0, "camera", "rate", o.rate, "be >= 0",
              "rate:=0 plays at the recorded stamps");
  CheckOption(o.rate_scale > 0.0, "camera", "rate_scale", o.rate_scale, "be > 0",
              "rate_scale:=1 plays at the recorded speed");
  CheckSize(o.width, o.height);
  runtime::CheckSizePair("camera", o.width, o.height,
                         "set both (centre-crop + resize) or neither (native size)");
}

void ValidateLive(const std::string& backend, const LiveSourceOptions& o) {
  if (backend == "aravis") {
    CheckSize(o.aravis.width, o.aravis.height);
    CheckOption(o.aravis.buffers >= 2, "camera", "buffers", o.aravis.buffers, "be >= 2",
                "stream buffers per device, e.g. buffers:=8");
    CheckOption(o.aravis.depth_scale > 0.0, "camera", "depth_scale", o.aravis.depth_scale,
                "be > 0", "metres per depth unit, e.g. depth_scale:=0.001");
  } else {
    CheckSize(o.libcamera.width, o.libcamera.height);
    CheckOption(o.libcamera.buffers >= 2, "camera", "buffers", o.libcamera.buffers, "be >= 2",
                "e.g. buffers:=4");
  }
  CheckOption(o.pose_mode == "topic" || o.pose_mode == "none", "camera", "pose_mode", o.pose_mode,
              "be topic or none", "pose_mode:=none publishes frames without a pose");
  CheckOption(o.pose_tolerance >= 0.0, "camera", "pose_tolerance", o.pose_tolerance,
              "be >= 0", "seconds, e.g. pose_tolerance:=0.05");
  CheckOption(o.pose_wait >= 0.0, "camera", "pose_wait", o.pose_wait, "be >= 0",
              "seconds, e.g. pose_wait:=0.2");
  CheckOption(o.max_pending >= 1, "camera", "max_pending", o.max_pending, "be >= 1",
              "e.g. max_pending:=8");
}

}  // namespace

CameraOptions CameraOptions::FromParameters(runtime::Parameters& params) {
  CameraOptions o;  // the defaults, written once in the field initialisers
  o.backend =
      params.Declare<std::string>("backend", o.backend, "sim | replay | aravis | libcamera");
  o.frame_id = params.Declare<std::string>("frame_id", o.frame_id, "frame of the images");
  if (o.backend == "sim") {
    DeclareSim(params, &o.sim);
  } else if (o.backend == "replay") {
    DeclareReplay(params, &o.replay);
  } else if (o.Live()) {
    DeclareLive(params, o.backend, &o.live);
  }
  return o;
}

void CameraOptions::Validate() const {
  if (backend == "sim") {
    ValidateSim(sim);
  } else if (backend == "replay") {
    ValidateReplay(replay);
  } else if (Live()) {
    ValidateLive(backend, live);
  } else {
    CheckOption(false, "camera", "backend", backend, "be sim, replay, aravis or libcamera",
                "e.g. backend:=sim");
  }
}

}  // namespace p2i::nodes
