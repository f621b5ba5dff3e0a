/// @file camera_options.h
/// @brief Every parameter of the camera node in one Options struct: defaults in the field
/// initialisers (written once), read from the node's parameters in one function, one Validate().
#pragma once

#include <string>

#include "nodes/camera/live_backend.h"
#include "nodes/runtime/parameters.h"

namespace p2i::nodes {

/// Largest image side the camera node serves (larger than any camera, and than the wire's
/// image limits allow to decode).
constexpr int kMaxCameraImageSide = 8192;

/// backend:=sim (SimSource): the synthetic scene rendered at poses from "pose" or along a
/// trajectory.
struct SimSourceOptions {
  std::string scene = "builtin:small_office";  ///< builtin:NAME or a scene YAML file
  bool kinect = false;                         ///< Kinect-like sensor noise and holes
  double rate = 20.0;                          ///< frames per second (> 0)
  int width = 0;   ///< 0 = the calibration's or 640
  int height = 0;  ///< 0 = the calibration's or 480
  std::string camera_info_file;  ///< ROS camera_info YAML; "" = the default pinhole
  std::string pose_mode = "topic";  ///< topic | trajectory
  std::string trajectory = "arm_sweep";  ///< pose_mode trajectory: the trajectory spec
  int trajectory_index = 0;  ///< which trajectory of a multi spec
  bool loop = true;          ///< pose_mode trajectory: restart at the end
  bool exit_at_end = false;  ///< stop the node when a non-looping trajectory ends
};

/// backend:=replay (ReplaySource): a dataset folder played at its recorded or a fixed rate.
struct ReplaySourceOptions {
  std::string dataset;           ///< the folder (required)
  std::string format = "auto";   ///< auto | capture | tum | 7scenes (scene::OpenDataset)
  int invalid_depth = 65535;     ///< 7-Scenes raw depth value meaning invalid
  std::string camera_info_file;  ///< overrides the dataset's calibration
  double rate = 0.0;             ///< frames per second; 0 = the recorded stamps
  double rate_scale = 1.0;       ///< speed factor on the recorded rate
  int width = 0;   ///< centre-crop + resize to this size; both 0 = native
  int height = 0;
  bool loop = false;         ///< start again at the end
  bool exit_at_end = false;  ///< stop the node at the end (no loop)
};

/// backend:=aravis | libcamera (LiveSource): a live device; frames get the pose at their stamp.
/// The stream size and buffers are the selected device's (aravis.width, libcamera.buffers...).
struct LiveSourceOptions {
  std::string camera_info_file;     ///< ROS camera_info YAML; "" = a nominal pinhole
  std::string pose_mode = "topic";  ///< topic (pose from "pose" by capture stamp) | none
  double pose_tolerance = 0.05;     ///< s: both poses bracketing a frame's stamp this close
  double pose_wait = 0.2;           ///< s: a frame may wait this long for a newer pose
  int max_pending = 8;              ///< frames waiting for a pose at most
  double stamp_offset = 0.0;        ///< s subtracted from the host reception stamp
  AravisOptions aravis;             ///< backend:=aravis (defaults in live_backend.h)
  LibcameraOptions libcamera;       ///< backend:=libcamera
};

/// The camera node's configuration (camera_node.h, README.md and docs/CAMERA.md list the
/// parameters). Only the selected backend's parameters are declared (and shown by --help), so a
/// parameter of another backend is refused as unknown. A value type: thread-compatible.
struct CameraOptions {
  std::string backend = "sim";     ///< sim | replay | aravis | libcamera
  std::string frame_id = "camera";  ///< frame of the images
  SimSourceOptions sim;
  ReplaySourceOptions replay;
  LiveSourceOptions live;

  /// Declares `backend`, `frame_id` and the parameters of the selected backend (name, type, the
  /// default of a default-constructed struct, description) and returns the values supplied or
  /// the defaults. Throws runtime::StartupError for a value of the wrong type.
  static CameraOptions FromParameters(runtime::Parameters& params);

  /// Throws std::invalid_argument naming the parameter, its bad value and how to fix it
  /// (runtime/option_error.h). Checks the selected backend's options only.
  void Validate() const;

  bool Live() const { return backend == "aravis" || backend == "libcamera"; }
};

}  // namespace p2i::nodes
