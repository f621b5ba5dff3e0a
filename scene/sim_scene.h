/// @file sim_scene.h
/// @brief The built-in synthetic indoor scene: a deterministic CPU renderer of RGB and metric
/// depth for any pose and camera (the `sim` camera backend, `p2i render`, test ground truth).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "scene/camera_info.h"
#include "scene/pose.h"
#include "scene/rgbd_sample.h"
#include "scene/sim_scene_description.h"
#include "scene/sim_sensor_options.h"

namespace p2i::scene {

/// Axis-aligned bounds in the world frame (metres).
struct SimBounds {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  bool Contains(const Eigen::Vector3d& p, double margin = 0.0) const {
    return (p.array() >= min.array() + margin).all() && (p.array() <= max.array() - margin).all();
  }
};

/// The camera's poses when the shutter opens and closes: motion blur spans the motion between.
struct SimExposure {
  Pose open;
  Pose close;
};

/// The shutter poses of frame `index` of a time-sorted `trajectory` for a shutter time centred on
/// its stamp, interpolated on the trajectory (held at its first and last pose beyond its ends).
SimExposure ExposureOnTrajectory(const std::vector<StampedPose>& trajectory, std::size_t index,
                                 double exposure_time_s);

/// Renders a room of textured boxes, cylinders and spheres with Lambertian shading (ambient plus
/// point/directional lights, no shadows) and, for materials with `specular` > 0, a Blinn-Phong
/// highlight that moves with the view, by rasterising each primitive's screen-space bounding
/// box with exact ray tests and a z-buffer, then shading each pixel once.
///
/// Conventions: world frame z up, floor at z = 0 (see SimSceneDescription). Poses are
/// camera-to-world with the OpenCV camera frame (x right, y down, looking along +z). The camera's
/// distortion coefficients are ignored (images are rendered undistorted with K).
/// Output: rgb CV_8UC3 in RGB order; depth CV_32FC1 z-depth in metres, 0 where nothing is hit
/// (or a sensor effect made a hole).
///
/// Rendering is a pure function of (scene, sensor options, pose, camera): same inputs, same
/// pixels, across calls and instances. Render() is const and thread-safe; set_sensor_options()
/// is not (configure before sharing the scene between threads).
class SimScene {
 public:
  explicit SimScene(SimSceneDescription description, SimSensorOptions sensor = {});

  static SimScene FromYamlFile(const std::string& path);
  static SimScene FromYamlString(const std::string& text, const std::string& source = "<string>");
  /// A scene embedded in the binary: "small_office" or "large_office" (the same text as
  /// scene/scenes/<name>.yaml). Throws std::invalid_argument naming the known scenes.
  static SimScene BuiltIn(const std::string& name = "small_office");
  static std::vector<std::string> BuiltInNames();
  /// The embedded YAML text of a built-in scene.
  static const std::string& BuiltInYaml(const std::string& name);
  /// What users write in parameters and on command lines: "builtin:NAME", a bare built-in name
  /// (when no file of that name exists), or a scene YAML file. Throws std::runtime_error listing
  /// the built-in scenes when `spec` is neither.
  static SimScene FromSpec(const std::string& spec);
  /// The sim camera (calib/sim.yaml: f = 525 at 640 px, centred principal point) at width x height.
  static CameraInfo DefaultCamera(int width = 640, int height = 480);
  /// This scene with every specular highlight removed (SimSceneDescription::Lambertian), same
  /// sensor options: the view-independent render.
  SimScene Lambertian() const { return SimScene(description_.Lambertian(), sensor_); }

  /// Renders the view from `camera_to_world`. `camera` must have positive size and focal
  /// lengths (std::invalid_argument otherwise). The sample's pose is the input pose, stamp 0.
  RgbdSample Render(const Pose& camera_to_world, const CameraInfo& camera) const;
  /// Same, for a frame captured at `stamp` seconds: the sample carries the stamp, and sensor
  /// noise also depends on it (a still camera gets fresh noise every frame, reproducibly).
  RgbdSample Render(const Pose& camera_to_world, const CameraInfo& camera, double stamp) const;
  /// Same, with motion blur over `exposure` when the sensor options' exposure_time_s is on
  /// (RGB averaged over the shutter poses, depth of `camera_to_world` with holes where the
  /// surface changed); equal open and close poses give the unblurred frame.
  RgbdSample Render(const Pose& camera_to_world, const CameraInfo& camera, double stamp,
                    const SimExposure& exposure) const;
  /// Frame `index` of `trajectory` at its stamp, with the motion blur of the camera's motion
  /// along it when the sensor options ask for it (ExposureOnTrajectory).
  RgbdSample RenderOnTrajectory(const std::vector<StampedPose>& trajectory, std::size_t index,
                                const CameraInfo& camera) const;

  /// The room's inner bounds.
  SimBounds Bounds() const;
  /// True when `point` is inside the room by at least `clearance` and no object is closer than
  /// `clearance` to it (objects are inflated by `clearance`).
  bool IsFree(const Eigen::Vector3d& point, double clearance = 0.0) const;

  const SimSceneDescription& description() const { return description_; }
  const SimSensorOptions& sensor_options() const { return sensor_; }
  void set_sensor_options(const SimSensorOptions& sensor);

 private:
  struct Compiled;
  SimSceneDescription description_;
  SimSensorOptions sensor_;
  RgbdSample RenderImpl(const Pose& camera_to_world, const CameraInfo& camera, double stamp,
                        bool stamped, const SimExposure* exposure) const;

  std::shared_ptr<const Compiled> compiled_;  // immutable after construction: shared by copies
};

}  // namespace p2i::scene
